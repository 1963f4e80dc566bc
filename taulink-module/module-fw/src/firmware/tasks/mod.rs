//! One task per concern; each owns its hardware.

pub mod radio;
pub mod status_led;
pub mod supervisor;
