//! Table of contents: clocks, board, then one task per concern.

mod board;
mod tasks;

use defmt::{error, info};
use embassy_executor::{SpawnError, SpawnToken, Spawner};
use {defmt_rtt as _, panic_probe as _};

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let p = embassy_nrf::init(board::clocks());
    info!("TauLink module firmware (nRF52840)");
    let board = board::Board::new(p);
    let Some(watchdog) = board.watchdog else {
        // Only possible if a previous image left the WDT running with another config; it
        // keeps counting and will reset us into a clean start.
        error!("watchdog already running with a foreign configuration");
        return;
    };
    spawn(
        &spawner,
        "supervisor",
        tasks::supervisor::supervisor_task(watchdog),
    );
    spawn(
        &spawner,
        "status_led",
        tasks::status_led::status_led_task(board.status_led),
    );
    spawn(&spawner, "radio", tasks::radio::radio_task(board.radio));
}

/// Starts a task. A task that cannot start never checks in with the supervisor, so the
/// watchdog resets the board: logged, not a panic.
fn spawn<S>(spawner: &Spawner, name: &str, token: Result<SpawnToken<S>, SpawnError>) {
    match token {
        Ok(token) => spawner.spawn(token),
        Err(e) => error!("cannot start task {}: {}", name, e),
    }
}
