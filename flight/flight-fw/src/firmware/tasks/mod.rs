//! One task per concern; each owns its hardware.

pub mod heartbeat;
pub mod radio;
pub mod supervisor;
