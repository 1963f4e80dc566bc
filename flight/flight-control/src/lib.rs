//! The flight controller's control laws and system identification: the LQG (RTKF
//! estimator + LQR), the PID baseline and the motor mixer ([`control`]), the shake, the
//! identification EKF and the autotune gains ([`sysid`]). Sans-IO, no globals.
//!
//! A crate of its own, re-exported as `flight_core::control` and `flight_core::sysid`: the
//! flight loop's hot numerics are built at `opt-level = 3` (the identification EKF's
//! matrix code is 2× slower at 2) while the rest of the flight core is built for size (see
//! the workspace manifest's profiles).
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod control;
pub mod sysid;

// The paths the modules use (`crate::model`, `crate::estimation`), as in `flight_core`.
use flight_estimation as estimation;
use lqg_design::model;
