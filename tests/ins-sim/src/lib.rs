//! Sensor simulator and log replay for the flight estimators: trajectories, IMU/mag/baro/GPS
//! models, a scenario runner that drives the INS, error metrics, and the PX4 replay format.
#![warn(missing_docs)]

pub mod compare;
pub mod flight_log;
pub mod magcal;
pub mod metrics;
pub mod noise;
pub mod plot;
pub mod replay;
pub mod scenario;
pub mod sensors;
pub mod sweep;
pub mod trajectory;

/// Element-wise combination of two 3-vectors.
#[must_use]
pub fn zip3(a: [f64; 3], b: [f64; 3], f: impl Fn(f64, f64) -> f64) -> [f64; 3] {
    let [a0, a1, a2] = a;
    let [b0, b1, b2] = b;
    [f(a0, b0), f(a1, b1), f(a2, b2)]
}

pub use scenario::{Sample, Scenario, Simulation};
