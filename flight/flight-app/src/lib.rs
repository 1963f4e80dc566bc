//! The flight controller's application, free of any HAL: `app::FlightApp`, which every
//! firmware task calls into (link hooks, bind, telemetry, console, the radio's device tool,
//! IMU fault policy, watchdog check-ins, save and gain-design requests, resume after a reset),
//! the shared task bodies (`app::link_task`), the telemetry reports, the flight log and who
//! may change settings. The flight loop it runs is `flight-core`'s, re-exported here under
//! its own names (`pipeline`, `settings`, …) so one path reaches both. Built for size: none
//! of this is on the loop's path (the workspace `Cargo.toml` has the measured reasons). The
//! sensor drivers are crates of their own under `flight/` (`mpu9250`, `ms5611`, `ubx`); the
//! UBX protocol, which the GPS port here drives, is re-exported as [`sensors::ubx`].
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod app;
pub mod authority;
pub mod gains;
pub mod logging;
pub mod report;
pub mod sensors;

pub use flight_core::{
    alerts, battery, board, control, estimation, loop_side, model, outputs, pipeline, settings,
    supervisor, sysid, vtx,
};
