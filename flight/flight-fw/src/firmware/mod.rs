//! Table of contents: clocks, board, settings, then one task per concern.

mod board;
mod outputs;
mod signals;
mod tasks;

use defmt::{error, info};
use embassy_executor::{SpawnError, SpawnToken, Spawner};
use flight_core::battery::{BatteryConfig, BatteryMonitor};
use flight_core::settings::Settings;
use {defmt_rtt as _, panic_probe as _};

use tasks::motors::protocol_from_settings;

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let p = embassy_stm32::init(board::clocks());
    info!("TauLink flight firmware on {}", board::BOARD);
    let board = board::Board::new(p);

    // Flash work first: a sector erase can stall the CPU longer than the watchdog timeout,
    // and the watchdog starts with the supervisor below.
    let (map, settings) = tasks::storage::open(board.settings_flash).await;
    let protocol = protocol_from_settings(&settings);
    let monitor = BatteryMonitor::new(battery_config(&settings));
    *signals::SETTINGS.lock().await = Some((settings.clone(), settings));
    if let Some(map) = map {
        spawn(&spawner, "storage", tasks::storage::storage_task(map));
    }

    spawn(
        &spawner,
        "supervisor",
        tasks::supervisor::supervisor_task(board.watchdog),
    );
    match board.motors.start(protocol) {
        Ok(motors) => spawn(&spawner, "motors", tasks::motors::motors_task(motors)),
        // Without the motor task the watchdog is never fed: reset, and the pins stay low.
        Err(e) => error!("motor outputs cannot run {}: {}", protocol, e),
    }
    spawn(
        &spawner,
        "heartbeat",
        tasks::heartbeat::heartbeat_task(board.heartbeat_led),
    );
    spawn(&spawner, "radio", tasks::radio::radio_task(board.radio));
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

fn battery_config(settings: &Settings) -> BatteryConfig {
    let cells = settings.u32("battery.cells") as u8;
    let current = settings.f32("battery.current_mv_per_a");
    BatteryConfig {
        voltage_divider: settings.f32("battery.divider"),
        current_mv_per_amp: (current > 0.0).then_some(current),
        cells: (cells > 0).then_some(cells),
        cell_warning_mv: settings.u32("battery.cell_warning_mv") as u16,
        cell_critical_mv: settings.u32("battery.cell_critical_mv") as u16,
        ..BatteryConfig::brushed_sparky()
    }
}

/// Starts a task. A task that cannot start never checks in with the supervisor, so the
/// watchdog resets the board: logged, not a panic.
fn spawn<S>(spawner: &Spawner, name: &str, token: Result<SpawnToken<S>, SpawnError>) {
    match token {
        Ok(token) => spawner.spawn(token),
        Err(e) => error!("cannot start task {}: {}", name, e),
    }
}
