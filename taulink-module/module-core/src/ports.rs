//! The seams where other crates plug into the module core: the air link (telemetry crate's
//! `link`, driven by the radio driver) and the handset telemetry encoders (telemetry crate's
//! `handset`: CRSF, S.Port, FrSky D). The core only ever talks to these traits.

use crate::channels::Channels;

/// What the link reports about itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStats {
    /// Packets are arriving from the other end.
    pub connected: bool,
    /// Received signal strength of the last packet, dBm.
    pub rssi_dbm: i16,
    /// Share of expected packets received over the last second, 0…100 %.
    pub link_quality_percent: u8,
}

/// The air link as the module core sees it.
pub trait LinkPort {
    /// Channels for the next uplink packet (transmitter role).
    fn send_channels(&mut self, channels: &Channels);
    /// Whether the link can take another uplink telemetry record now.
    fn can_send_record(&self) -> bool;
    /// A record for the other end (phone → flight side); only called after
    /// `can_send_record` said yes.
    fn send_record(&mut self, record: &[u8]);
    /// The current statistics.
    fn stats(&self) -> LinkStats;
    /// Start the bind procedure.
    fn start_bind(&mut self);
}

/// The handset telemetry encoder (CRSF, S.Port or FrSky D, chosen by the settings).
pub trait HandsetOutput {
    /// A telemetry record from the flight side.
    fn on_telemetry(&mut self, record: &[u8]);
    /// Link statistics at `now_ms`; the encoder paces its own frames (S.Port pushes RSSI
    /// at least once a second, CRSF sends LINK_STATISTICS in step with the link).
    fn on_link_stats(&mut self, stats: &LinkStats, now_ms: u32);
}
