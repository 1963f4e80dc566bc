//! Sensor simulator and log replay for the flight estimators: trajectories, IMU/mag/baro/GPS models, the PX4 replay format.
#![warn(missing_docs)]
