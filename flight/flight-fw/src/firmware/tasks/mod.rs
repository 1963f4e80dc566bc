//! One task per concern; each owns its hardware.

pub mod alerts;
pub mod battery;
pub mod console;
pub mod heartbeat;
pub mod motors;
pub mod radio;
pub mod storage;
pub mod supervisor;
