//! TauLink flight firmware for the STM32F405 (BrushedSparky; Sparky2 with `--features sparky2`).
//!
//! All behaviour lives in `flight-core`; this crate only wires the board to it. On the host
//! it compiles to an empty program so that `cargo test --workspace` never builds a HAL.
//!
//! The pipeline: at boot the stored settings become a `pipeline::FlightSetup` and the LQG/PID
//! gains are solved (arming waits for them). The MPU9250's data-ready edge (1 kHz) wakes the
//! IMU task, which reads the sample, runs `FlightLoop::step` (complementary attitude filter,
//! supervisor, flight mode, controller, mixer) and hands the commands to the motor task at
//! once, so outputs follow each gyro sample (OneShot125 fires then). The link task runs the
//! TauLink follower on the RFM22B and feeds the loop its sticks; telemetry (attitude,
//! battery, link quality, mode, arm/failsafe, identification) and setting changes travel on
//! the link's stream. The baro task supplies the climb rate for the failsafe descent; the
//! battery and alert tasks sound the alarms and announcements through the DAC. Every task
//! checks in with the watchdog supervisor. The same logic flies in `tests/flight-sitl`.
//!
//! Image sizes: the table in the top-level README, written by `cargo xtask readme` and checked by
//! `cargo xtask verify`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware;

#[cfg(not(target_os = "none"))]
fn main() {}
