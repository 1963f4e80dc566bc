//! Simulated airframes for the flight controllers: a per-axis plant and a 6-DoF quadrotor with
//! motor lag, latency, gyro noise and saturation, plus the closed-loop and identification
//! experiments that prove the flight-core control stack (see README.md).
#![warn(missing_docs)]

pub mod axis;
pub mod cli;
pub mod closed_loop;
pub mod esc;
pub mod experiments;
pub mod ground;
pub mod identify;
pub mod plot;
pub mod quad;
pub mod stats;
