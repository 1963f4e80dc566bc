//! The RFM22B driver as the link's `PacketRadio`: the shared adapter of
//! `radio-rfm22b`'s `telemetry` feature (`radio_rfm22b::link`), which the flight side and
//! the host simulations use too, so both ends always agree on the chip setup.

pub use radio_rfm22b::link::{LinkRadio, LinkRadioError, modem_for, packet_config};
