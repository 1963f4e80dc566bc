//! Table of contents: clocks, board, settings → flight setup and solved gains, then one task
//! per concern: imu (the flight loop, driven by the MPU9250's data-ready), motors, link (the
//! TauLink follower on the RFM22B), baro, gains (re-solve after setting changes), battery,
//! alerts, console, storage, heartbeat and the watchdog supervisor. See `signals` for the
//! data flow.

mod board;
mod imu_bus;
mod link_radio;
mod outputs;
mod signals;
mod tasks;

use defmt::{error, info};
use embassy_executor::{SpawnError, SpawnToken, Spawner};
use flight_core::battery::BatteryMonitor;
use flight_core::pipeline::{Controllers, from_settings};
use flight_core::settings::Settings;
use {defmt_rtt as _, panic_probe as _};

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let p = embassy_stm32::init(board::clocks());
    info!("TauLink flight firmware on {}", board::BOARD);
    let board = board::Board::new(p);

    // Flash work first: a sector erase can stall the CPU longer than the watchdog timeout,
    // and the watchdog starts with the supervisor below.
    let (map, settings) = tasks::storage::open(board.settings_flash).await;
    // Settings → configuration; the gains are solved here, before anything can arm. Stored
    // settings that do not make a flyable setup fall back to the factory ones.
    let setup = match from_settings(&settings) {
        Ok(s) => s,
        Err(e) => {
            error!("stored settings not flyable ({}): factory setup", e);
            match from_settings(&Settings::default()) {
                Ok(s) => s,
                Err(_) => return, // the table's own defaults are tested flyable
            }
        }
    };
    let controllers = match Controllers::design(&setup.control) {
        Ok(c) => Some(c),
        Err(e) => {
            error!("gain design failed ({}): arming refused", e);
            None
        }
    };
    let monitor = BatteryMonitor::new(setup.battery);
    *signals::SETTINGS.lock().await = Some((settings.clone(), settings));
    if let Some(map) = map {
        spawn(&spawner, "storage", tasks::storage::storage_task(map));
    }

    spawn(
        &spawner,
        "supervisor",
        tasks::supervisor::supervisor_task(board.watchdog),
    );
    match board.motors.start(setup.protocol) {
        Ok(motors) => spawn(&spawner, "motors", tasks::motors::motors_task(motors)),
        // Without the motor task the watchdog is never fed: reset, and the pins stay low.
        Err(e) => error!("motor outputs cannot run {}: {}", setup.protocol, e),
    }
    spawn(
        &spawner,
        "imu",
        tasks::imu::imu_task(board.imu, setup, controllers),
    );
    spawn(&spawner, "link", tasks::link::link_task(board.radio));
    spawn(&spawner, "baro", tasks::baro::baro_task(board.baro));
    spawn(&spawner, "gains", tasks::gains::gains_task());
    spawn(
        &spawner,
        "heartbeat",
        tasks::heartbeat::heartbeat_task(board.heartbeat_led),
    );
    spawn(
        &spawner,
        "battery",
        tasks::battery::battery_task(board.battery, monitor),
    );
    spawn(
        &spawner,
        "alerts",
        tasks::alerts::alerts_task(board.speaker),
    );
    spawn(&spawner, "console", tasks::console::console_task(board.usb));
}

/// Starts a task. A task that cannot start never checks in with the supervisor, so the
/// watchdog resets the board: logged, not a panic.
fn spawn<S>(spawner: &Spawner, name: &str, token: Result<SpawnToken<S>, SpawnError>) {
    match token {
        Ok(token) => spawner.spawn(token),
        Err(e) => error!("cannot start task {}: {}", name, e),
    }
}
