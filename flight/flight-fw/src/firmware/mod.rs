//! Table of contents: clocks, board, settings → flight setup and solved gains, then one task
//! per concern: imu (the flight loop, driven by the MPU9250's data-ready), motors, link (the
//! TauLink follower on the RFM22B), baro, gains (re-solve after setting changes), battery,
//! alerts, console, storage, heartbeat and the watchdog supervisor. Every decision is in
//! `flight_core::app::FlightApp` (installed in `shared`); the tasks only move data between
//! their peripheral and the app. See `shared` for the data flow.

mod board;
mod imu_bus;
mod link_radio;
mod outputs;
mod shared;
mod tasks;
mod usb_cdc;

use defmt::{error, info};
use embassy_executor::{SpawnError, SpawnToken, Spawner};
use flight_core::app::FlightApp;
use mpu9250::SampleRate;
use {defmt_rtt as _, panic_probe as _};

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let p = embassy_stm32::init(board::clocks());
    info!("TauLink flight firmware on {}", board::BOARD);
    let board = board::Board::new(p);

    // Flash work first: a sector erase can stall the CPU longer than the watchdog timeout,
    // and the watchdog starts with the supervisor below.
    let (map, settings, problem) = tasks::storage::open(board.settings_flash).await;
    // The application: settings → setup (factory setup if the stored one does not fly) and
    // the solved gains, before anything can arm.
    let Some(mut app) = FlightApp::new(settings, shared::now_ms()) else {
        error!("no flyable setup, not even the factory one");
        return;
    };
    if let Some(problem) = problem {
        // Console, telemetry and arming all see it until the pilot saves a set.
        app.on_settings_problem(problem);
    }
    // The link's secrets every boot (spec §12): the phone changes' session, the epoch nonces'
    // seed and each bind's CPace randomness, from 32 bytes of the hardware RNG.
    let mut rng = board.rng;
    let mut random = [0u8; 32];
    for word in random.chunks_exact_mut(4) {
        word.copy_from_slice(&rng.next_u32().to_le_bytes());
    }
    app.seed_random(&random);
    if let Some(e) = app.setup_error() {
        error!("stored settings not flyable ({}): factory setup", e);
    }
    let setup = *app.setup();
    shared::install(app);
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
        tasks::imu::imu_task(board.imu, sample_rate(setup.loop_rate_hz)),
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
        tasks::battery::battery_task(board.battery),
    );
    spawn(
        &spawner,
        "alerts",
        tasks::alerts::alerts_task(board.speaker),
    );
    spawn(&spawner, "console", tasks::console::console_task(board.usb));
    #[cfg(feature = "sparky2")]
    match board.gps {
        Some(gps) => spawn(&spawner, "gps", tasks::gps::gps_task(gps)),
        None => error!("GPS port unavailable"),
    }
}

/// The MPU9250's sample rate for the loop rate.
fn sample_rate(loop_rate_hz: u32) -> SampleRate {
    if loop_rate_hz >= 1000 {
        SampleRate::Hz1000
    } else {
        SampleRate::Hz500
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
