//! Table of contents: the reset's cause and record (`fault`), clocks (HSE probe, flash
//! accelerator), board, settings → flight setup and solved gains, then one task
//! per concern: imu (the flight loop, driven by the MPU9250's data-ready), motors, link (the
//! TauLink follower on the RFM22B), baro, gains (re-solve after setting changes), battery,
//! alerts, console, storage, heartbeat and the watchdog supervisor. Every decision is in
//! `flight_app::app::FlightApp` (installed in `shared`); the tasks only move data between
//! their peripheral and the app. See `shared` for the data flow.

mod board;
mod clocks;
mod fault;
mod i2c_bus;
mod imu_bus;
mod link_radio;
mod outputs;
mod seeds;
mod shared;
mod tasks;
mod usb_cdc;

use defmt::{error, info, warn};
use defmt_rtt as _;
use embassy_executor::{InterruptExecutor, SendSpawner, SpawnError, SpawnToken, Spawner};
use embassy_stm32::interrupt;
use embassy_stm32::interrupt::{InterruptExt, Priority};
use flight_app::app::resume::{self, Kept, ResetCause, Resume};
use flight_app::app::{BootFacts, FlightApp};
use flight_app::pipeline::from_settings;
use flight_app::settings::Settings;
use mpu9250::SampleRate;

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    // Before anything can reset again: why this boot, and what the last one left.
    let cause = fault::reset_cause();
    let kept = fault::take();
    let source = clocks::probe();
    let p = embassy_stm32::init(clocks::config(source));
    // The PIL's `flash-slow` variant (flight-fw `build.rs`) leaves it off.
    if !cfg!(pil_flash_slow) {
        clocks::accelerate_flash();
    }
    info!("TauLink flight firmware on {}", board::BOARD);
    if source == clocks::Clocks::HsiFallback {
        error!(
            "HSE did not start within {} ms: running from the HSI",
            clocks::HSE_WAIT_MS
        );
    }
    let board = board::Board::new(p);

    // Flash work first: a sector erase can stall the CPU longer than the watchdog timeout,
    // and the watchdog starts with the supervisor below.
    let (map, settings, problem) = tasks::storage::open(board.settings_flash).await;
    // A reset in the air with a fresh record resumes the flight with the record's gains;
    // otherwise the application: settings → setup (factory setup if the stored one does not
    // fly) and the solved gains, before anything can arm.
    let Some(app) = boot_app(cause, &kept, settings) else {
        error!("no flyable setup, not even the factory one");
        return;
    };
    let resuming = app.resumed().is_some();
    if resuming {
        warn!("reset in the air ({}): flight resumed", cause);
    }
    if let Some(problem) = problem {
        // Console, telemetry and arming all see it until the pilot saves a set.
        app.on_settings_problem(problem);
    }
    // The link's secrets every boot (spec §12): the phone changes' session, the epoch nonces'
    // seed and each bind's CPace randomness, from 32 bytes of the hardware RNG (bounded: the
    // unique ID and cycle counter when it gives nothing).
    let (words, rng_fallback) = seeds::seeds::<8>(board.rng);
    let mut random = [0u8; 32];
    for (bytes, word) in random.chunks_exact_mut(4).zip(words) {
        bytes.copy_from_slice(&word.to_le_bytes());
    }
    app.seed_random(&random);
    if rng_fallback {
        error!("RNG gave nothing: seeds from the unique ID and timing");
    }
    app.on_boot_facts(BootFacts {
        clock_fallback: source == clocks::Clocks::HsiFallback,
        rng_fallback,
    });
    if let Some(e) = app.setup_error() {
        error!("stored settings not flyable ({}): factory setup", e);
    }
    let setup = *app.setup();
    // The loop's side goes to its own executor; the rest of the app to the tasks.
    let side = shared::loop_side(app);
    shared::install(app);
    if let Some(map) = map {
        spawn(&spawner, "storage", tasks::storage::storage_task(map));
    }

    spawn(
        &spawner,
        "supervisor",
        tasks::supervisor::supervisor_task(board.watchdog),
    );
    let motors = match board.motors.start(setup.protocol) {
        Ok(motors) => Some(motors),
        // The pins stay low; the loop flies on without them.
        Err(e) => {
            error!("motor outputs cannot run {}: {}", setup.protocol, e);
            None
        }
    };
    spawn(
        &spawner,
        "loop report",
        tasks::loop_report::loop_report_task(),
    );
    match side {
        Some(side) => {
            let token = tasks::imu::imu_task(
                board.imu,
                sample_rate(setup.loop_rate_hz),
                resuming,
                side,
                motors,
            );
            match token {
                Ok(token) => loop_executor().spawn(token),
                Err(e) => error!("cannot start the flight loop: {}", e),
            }
        }
        None => error!("the flight loop's side is gone"),
    }
    spawn(&spawner, "link", tasks::link::link_task(board.radio));
    spawn(&spawner, "baro", tasks::baro::baro_task(board.baro));
    spawn(&spawner, "gains", tasks::gains::gains_task());
    spawn(
        &spawner,
        "heartbeat",
        tasks::heartbeat::heartbeat_task(board.heartbeat_led, board.alarm_led, board.link_led),
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
    #[cfg(not(feature = "sparky2"))]
    spawn(&spawner, "vtx", tasks::vtx::vtx_task(board.vtx));
    #[cfg(feature = "sparky2")]
    match board.gps {
        Some(gps) => spawn(&spawner, "gps", tasks::gps::gps_task(gps)),
        None => error!("GPS port unavailable"),
    }
}

/// The application for this boot, built in its static storage: the flight the no-init
/// record describes resumed when it says so (`flight_app::app::resume::plan`) and its
/// settings make a setup, else the stored settings' (the factory's if they do not fly) with
/// freshly solved gains.
fn boot_app(
    cause: ResetCause,
    kept: &fault::Record,
    settings: Settings,
) -> Option<&'static mut FlightApp> {
    let kept = Kept {
        state: &kept.state,
        gains: &kept.gains,
        fault: &kept.fault,
        feed: &kept.feed,
    };
    match resume::plan(cause, &kept) {
        // The PIL's `no-resume` variant (flight-fw `build.rs`) boots cold after any reset.
        Ok(_) if cfg!(pil_no_resume) => new_app(settings),
        Ok(r) if from_settings(&r.settings).is_ok() => resumed_app(settings, &r),
        Ok(_) => {
            info!("boot after {}: the record's settings make no setup", cause);
            new_app(settings)
        }
        Err(why) => {
            info!("boot after {}: {}", cause, why);
            new_app(settings)
        }
    }
}

// One builder per frame, neither inlined: the app (≈ 16 KiB) is built in each and written
// to its storage, so the boot's stack holds one copy, not one per way of making it.
#[inline(never)]
fn resumed_app(settings: Settings, r: &Resume) -> Option<&'static mut FlightApp> {
    shared::create(|| FlightApp::resume(settings, r, shared::now_ms()))
}

#[inline(never)]
fn new_app(settings: Settings) -> Option<&'static mut FlightApp> {
    shared::create(|| FlightApp::new(settings, shared::now_ms()))
}

/// The flight loop's executor: UART5's interrupt (unused on both boards), above every
/// thread-mode task and below the HAL's interrupt handlers (priority 0), which only wake
/// tasks.
static LOOP_EXECUTOR: InterruptExecutor = InterruptExecutor::new();

#[interrupt]
unsafe fn UART5() {
    // SAFETY: the executor's own interrupt, started before it can fire (`loop_executor`).
    unsafe { LOOP_EXECUTOR.on_interrupt() }
}

/// Starts the flight loop's executor.
fn loop_executor() -> SendSpawner {
    interrupt::UART5.set_priority(Priority::P6);
    LOOP_EXECUTOR.start(interrupt::UART5)
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
