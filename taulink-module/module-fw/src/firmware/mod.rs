//! Table of contents: clocks (bounded crystal start-up, REGOUT0), board, settings, the module core, then one task per concern.

mod board;
mod clocks;
mod fault;
mod link_radio;
mod shared;
mod tasks;

use defmt::{error, info, warn};
use defmt_rtt as _;
use embassy_embedded_hal::adapter::BlockingAsync;
use embassy_executor::{SpawnError, SpawnToken, Spawner};
use embassy_nrf::nvmc::Nvmc;
use module_core::app::App;
use module_core::settings::{InputProtocol, Role, Settings, SettingsStore};

use tasks::supervisor::Watched;

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let last_fault = fault::take();
    let (config, clocks) = clocks::probe(board::config());
    let p = embassy_nrf::init(config);
    info!("TauLink module firmware (nRF52840)");
    if let Some(f) = last_fault {
        warn!("the last boot ended in a fault: {}", f);
    }
    if clocks.high != clocks::HighClock::Crystal || clocks.low != clocks::LowClock::Crystal {
        error!("crystal did not start: {}", clocks);
    }
    let board = board::Board::new(p);
    let Some(watchdog) = board.watchdog else {
        // Only possible if a previous image left the WDT running with another config; it
        // keeps counting and will reset us into a clean start.
        error!("watchdog already running with a foreign configuration");
        return;
    };
    // First, so the watchdog is fed while the settings load.
    match tasks::supervisor::supervisor_task(watchdog) {
        Ok(token) => spawner.spawn(token),
        Err(e) => error!("cannot start the supervisor: {}", e),
    }

    let flash = BlockingAsync::new(Nvmc::new(board.nvmc));
    let Ok(mut store) = SettingsStore::new(flash, board::SETTINGS_FLASH) else {
        error!("settings flash range rejected");
        return;
    };
    let settings = match store.load().await {
        Ok(Some(settings)) => settings,
        Ok(None) => Settings::default(),
        Err(e) => {
            warn!("settings unreadable ({}), using defaults", e);
            Settings::default()
        }
    };
    info!("settings: {}", settings);
    match App::new(
        settings,
        module_core::air::AirLink::new(),
        module_core::handset::Handset::new(&settings),
        false,
    ) {
        Ok(app) => shared::install(app),
        Err(e) => error!("module core refused its configuration: {}", e),
    }

    spawn(
        &spawner,
        Watched::StatusLed,
        tasks::status_led::status_led_task(board.status_led),
    );
    spawn(
        &spawner,
        Watched::Radio,
        tasks::link::link_task(board.radio, settings),
    );
    spawn(&spawner, Watched::App, tasks::app::app_task());
    spawn(
        &spawner,
        Watched::Button,
        tasks::button::button_task(board.bind_button),
    );
    spawn(
        &spawner,
        Watched::Battery,
        tasks::battery::battery_task(board.battery),
    );
    spawn(
        &spawner,
        Watched::Settings,
        tasks::settings::settings_task(store),
    );
    spawn(&spawner, Watched::Hm10, tasks::hm10::hm10_task(board.hm10));
    match settings.role {
        Role::Transmitter => {
            spawn(
                &spawner,
                Watched::JrLine,
                tasks::jr_line::jr_line_task(board.jr_line),
            );
            if settings.input == InputProtocol::Ppm {
                spawn(
                    &spawner,
                    Watched::PpmIn,
                    tasks::ppm_in::ppm_in_task(board.ppm_in),
                );
            }
        }
        Role::Receiver => {
            spawn(
                &spawner,
                Watched::PpmOut,
                tasks::ppm_out::ppm_out_task(board.ppm_out),
            );
        }
    }
}

/// Registers a task with the supervisor and starts it. A task that cannot start is logged;
/// it is then not expected to check in.
fn spawn<S>(spawner: &Spawner, task: Watched, token: Result<SpawnToken<S>, SpawnError>) {
    match token {
        Ok(token) => {
            tasks::supervisor::expect(task);
            spawner.spawn(token);
        }
        Err(e) => error!("cannot start task {}: {}", task, e),
    }
}
