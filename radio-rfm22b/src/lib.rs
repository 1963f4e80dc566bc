//! Driver for the Silicon Labs Si4432 (HopeRF RFM22B) sub-GHz transceiver.
//!
//! `no_std`, generic over embedded-hal 1.0 (`SpiDevice`, `DelayNs`, `OutputPin`) and
//! embedded-hal-async (`SpiDevice`, `Wait`); it knows nothing of embassy, so it runs on any
//! HAL, on a Linux spidev, or against the virtual Si4432 in `tests/si4432-sim`.
#![cfg_attr(not(test), no_std)]
#![deny(unsafe_code)]
#![warn(missing_docs)]

mod bus;
mod error;
#[cfg(feature = "openlrs")]
pub mod openlrs;
mod probe;
pub mod registers;

pub use bus::Bus;
pub use error::Error;
pub use probe::{ChipInfo, Version, probe, software_reset};
