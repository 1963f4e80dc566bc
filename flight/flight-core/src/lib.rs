//! The flight controller's behaviour, free of any HAL: estimation, control, the
//! arming/failsafe supervisor and the application the firmware's tasks call into. The
//! firmware crate only wires peripherals to what lives here, so everything here runs in host
//! tests. The sensor drivers are crates of their own under `flight/` (`mpu9250`, `ms5611`,
//! `ubx`); the UBX protocol, which the GPS port here drives, is re-exported as [`sensors::ubx`].
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod alerts;
pub mod app;
pub mod authority;
pub mod battery;
pub mod board;
pub use flight_control::control;
pub use flight_estimation as estimation;
pub mod logging;
pub use lqg_design::model;
pub mod outputs;
pub mod pipeline;
pub mod report;
pub mod sensors;
pub mod settings;
pub mod supervisor;
pub use flight_control::sysid;
pub mod vtx;
