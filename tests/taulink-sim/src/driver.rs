//! The link's radio and clock on the chip simulator: the driver's own link adapter
//! (`radio_rfm22b::link::LinkRadio`) and the boards' `SimClock` (sim-exec's, the `LinkClock`
//! on virtual time the packet world uses too) put the link code on `radio-rfm22b` over
//! `si4432-sim`.

pub use radio_rfm22b::link::{LinkRadio, LinkRadioError, modem_for, packet_config};
pub use si4432_sim::SimClock;
