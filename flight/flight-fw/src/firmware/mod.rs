//! Table of contents: clocks, board, then one task per concern.

mod board;
mod tasks;

use defmt::{error, info};
use embassy_executor::{SpawnError, SpawnToken, Spawner};
use {defmt_rtt as _, panic_probe as _};

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let p = embassy_stm32::init(board::clocks());
    info!("TauLink flight firmware on {}", board::BOARD);
    let board = board::Board::new(p);

    // The supervisor owns the watchdog. It must start after anything that can stall flash
    // for longer than the watchdog timeout (a settings sector erase): none of that happens
    // before this point yet, and whatever is added later goes above this line.
    spawn(
        &spawner,
        "supervisor",
        tasks::supervisor::supervisor_task(board.watchdog),
    );
    spawn(
        &spawner,
        "heartbeat",
        tasks::heartbeat::heartbeat_task(board.heartbeat_led),
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
