//! One task per concern; each owns its hardware and hands its data to `FlightApp`.

pub mod alerts;
pub mod baro;
pub mod battery;
pub mod console;
pub mod gains;
#[cfg(feature = "sparky2")]
pub mod gps;
pub mod heartbeat;
pub mod imu;
pub mod link;
pub mod loop_report;
pub mod motors;
pub mod storage;
pub mod supervisor;
