//! The flight controller's flight loop and what it is made of, free of any HAL: the
//! estimators' and control laws' stages, the arming/failsafe supervisor, the mixer and
//! outputs, alerts, the battery monitor, and the settings that configure them. Built for
//! speed (the loop's path); the application around it — link hooks, console, telemetry,
//! logging, the task bodies — is `flight-app`, built for size. Everything here runs in host
//! tests.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod alerts;
pub mod battery;
pub mod board;
pub use flight_control::control;
pub use flight_estimation as estimation;
pub use lqg_design::model;
pub mod loop_side;
pub mod outputs;
pub mod pipeline;
pub mod settings;
pub mod supervisor;
pub use flight_control::sysid;
pub mod vtx;
