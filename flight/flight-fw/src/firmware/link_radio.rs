//! The link's clock and radio: the driver's own adapters, `radio_rfm22b::link::EmbassyClock`
//! (embassy-time's 1 MHz tick here), `radio_rfm22b::link::LinkRadio` and
//! `openlrs::dual::DualRadio`, shared with the module firmware and the host simulations so
//! both ends always set the chip up the same way.

pub use radio_rfm22b::link::EmbassyClock;
