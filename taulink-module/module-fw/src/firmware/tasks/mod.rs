//! One task per concern; each owns its hardware.

pub mod app;
pub mod battery;
pub mod button;
pub mod hm10;
pub mod jr_line;
pub mod link;
pub mod ppm_in;
pub mod ppm_out;
pub mod settings;
pub mod status_led;
pub mod supervisor;
