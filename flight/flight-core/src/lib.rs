//! The flight controller's behaviour, free of any HAL: sensor drivers over embedded-hal,
//! estimation, control and the arming/failsafe supervisor. The firmware crate only wires
//! peripherals to what lives here, so everything here runs in host tests.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod alerts;
pub mod app;
pub mod authority;
pub mod battery;
pub mod board;
pub mod control;
pub mod estimation;
pub mod model;
pub mod outputs;
pub mod pipeline;
pub mod report;
pub mod sensors;
pub mod settings;
pub mod supervisor;
pub mod sysid;
