//! TauLink's messages and wire formats: what travels over the air between the module and
//! the flight controller, and what the module speaks to the handset. Pure `no_std` code,
//! no radio and no async: the radio driver and the firmware crates plug into it.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod checksum;
pub mod handset;
