//! Simulated airframes for the flight controllers: a per-axis plant and a 6-DoF quadrotor with
//! motor lag, latency, gyro noise and saturation.
#![warn(missing_docs)]
