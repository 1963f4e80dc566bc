//! TauLink flight firmware for the STM32F405 (BrushedSparky; Sparky2 with `--features sparky2`).
//!
//! All behaviour lives in `flight-core`'s application, `flight_app::app::FlightApp`; this
//! crate only wires the board to it: every task moves bytes or samples between a peripheral
//! and the app (shared behind a thread-mode mutex, `firmware::shared`), the flight loop's
//! side of the app runs in its own interrupt executor. On the host it compiles to an empty
//! program so that `cargo test --workspace` never builds a HAL.
//!
//! The pipeline: at boot the stored settings are loaded and the app designs its gains
//! (arming waits for them); a problem with the stored settings goes to the app, which
//! refuses to arm until the pilot saves a set. The MPU9250's data-ready (1 kHz) wakes the IMU
//! task in the loop's interrupt executor, which reads the sample, runs `LoopSide::step` (the
//! flight loop and the IMU fault policy) and sets the motor timers at once, so outputs follow
//! each gyro sample (OneShot125 fires then). The link task runs the TauLink follower on the RFM22B with
//! the app as its hooks (sticks in, telemetry and setting changes over the link's stream).
//! The baro, battery, alert, console, storage and gains tasks each call their `on_*` method;
//! the supervisor task feeds the independent watchdog only when the app says every task
//! checked in. The same app flies in `tests/flight-sitl`.
//!
//! Image sizes: the table in the top-level README, written by `cargo xtask readme` and checked by
//! `cargo xtask verify`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware;

#[cfg(not(target_os = "none"))]
fn main() {}
