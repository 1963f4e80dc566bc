//! The TauLink module's behaviour, free of any HAL: reading the handset (PPM, CRSF),
//! driving the link as its timing master (or as a receiver), and fanning telemetry out to
//! the handset and the HM-10. The firmware crate only wires nRF52840 peripherals to it.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod air;
pub mod app;
pub mod battery;
pub mod button;
pub mod channels;
pub mod handset;
pub mod hm10;
pub mod link_task;
pub mod params;
pub mod phrase;
pub mod ports;
pub mod ppm;
pub mod records;
pub mod session;
pub mod settings;
pub mod status;
pub mod watchdog;
