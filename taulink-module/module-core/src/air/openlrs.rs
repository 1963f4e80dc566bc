//! The module as an OpenLRSng transmitter (`settings.protocol` OpenLRSng): the same
//! [`AirLink`] the TauLink master feeds, here fed by `openlrs`'s TX role.
//! Before each packet the handset's channels (10-bit OpenLRSng values) and queued phone
//! records go into the [`Transmitter`]; after each step the downlink comes out: OpenLRSng's
//! link-info frames become the link statistics the handset shows (CRSF link statistics,
//! S.Port RSSI) and its serial passthrough bytes the telemetry records (the flight side
//! sends TauLink's message stream through it, `flight_app::app::openlrs`).
//!
//! Input loss: the transmitter stops sending once the handset's channels are older than the
//! input timeout (`Transmitter::with_stale_input_stop`: OpenLRSng's `ppmAge`), so the
//! receiver flies its failsafe instead of stale sticks. OpenLRSng frames carry no
//! authentication.
//!
//! [`run_openlrs_transmitter`] is the role loop the firmware and the simulator share.

use openlrs::channels::ticks_to_bits;
use openlrs::quality::{quality_percent, rssi_dbm};
use openlrs::roles::TxEvent;
use openlrs::tx::{Received, Transmitter};

use super::{AirLink, CONNECTED_TIMEOUT_US};
use crate::channels::MAX_CHANNELS;
use crate::ports::LinkStats;
use crate::records::MAX_STREAM_FRAME_LEN;

/// `LinkStats::rate_code` of an OpenLRSng link: this plus the modem profile (0..4), clear of
/// TauLink's rate codes (the flight side's `OPENLRS_RATE_CODE_BASE`).
pub const OPENLRS_RATE_CODE_BASE: u8 = 0x10;

impl AirLink {
    /// Right before an OpenLRSng packet is built: fresh handset channels (none once the
    /// input is lost, so the transmitter goes quiet) and phone records for the serial uplink.
    pub fn on_openlrs_send(&mut self, tx: &mut Transmitter) {
        if let Some(channels) = self.channels.filter(|_| !self.input_lost) {
            let mut bits = [0u16; MAX_CHANNELS];
            for (slot, value) in bits.iter_mut().zip(channels.as_slice()) {
                *slot = ticks_to_bits(*value);
            }
            tx.set_channels(bits.get(..channels.as_slice().len()).unwrap_or(&bits));
        }
        while tx.serial_free() >= MAX_STREAM_FRAME_LEN {
            let mut frame = [0u8; MAX_STREAM_FRAME_LEN];
            let Some(stream) = self.pop_uplink_frame(&mut frame) else {
                break;
            };
            tx.queue_serial(stream);
        }
    }

    /// After an OpenLRSng step at `now_us` with what it reported: input freshness, telemetry
    /// bytes to records, and the link statistics.
    pub fn on_openlrs_step(&mut self, now_us: u64, tx: &Transmitter, events: &[TxEvent]) {
        self.update_input(now_us);
        let mut rssi = None;
        for event in events {
            if let TxEvent::Downlink {
                received,
                rssi: raw,
            } = event
            {
                self.last_downlink_us = Some(now_us);
                rssi = Some(rssi_dbm(*raw));
                match received {
                    Received::LinkInfo(info) => {
                        self.openlrs_remote =
                            Some((rssi_dbm(info.rssi), quality_percent(info.link_quality)));
                    }
                    Received::Serial(bytes) => {
                        let mut bytes = bytes.iter().copied();
                        self.read_stream(|buf| {
                            let mut n = 0;
                            for (slot, byte) in buf.iter_mut().zip(bytes.by_ref()) {
                                *slot = byte;
                                n += 1;
                            }
                            n
                        });
                    }
                    Received::Duplicate | Received::Invalid(_) => {}
                }
            }
        }
        let connected = self
            .last_downlink_us
            .is_some_and(|t| now_us.saturating_sub(t) < CONNECTED_TIMEOUT_US);
        let remote = self.openlrs_remote.filter(|_| connected);
        self.stats = LinkStats {
            connected,
            rssi_dbm: rssi.unwrap_or(self.stats.rssi_dbm),
            link_quality_percent: quality_percent(tx.link_quality()),
            remote_rssi_dbm: remote.map_or(0, |(dbm, _)| dbm),
            remote_link_quality_percent: remote.map(|(_, lq)| lq),
            rate_code: OPENLRS_RATE_CODE_BASE + tx.bind_data().modem_profile,
            schedule: None,
            // OpenLRSng frames carry no tag.
            tag_failures: 0,
            // OpenLRSng sends at its bind data's power (no dynamic power).
            tx_power_step: None,
        };
    }
}

/// The module's OpenLRSng transmitter loop, shared by the firmware and the simulator: the
/// crate's `tx_start`, then `tx_step` forever, `before_send` right before each packet
/// ([`AirLink::on_openlrs_send`] through the app) and `on_step(now_us, tx, events)` after
/// each step ([`crate::app::App::on_openlrs_step`]). Returns only on a radio error.
pub use openlrs::roles::run_transmitter_steps as run_openlrs_transmitter;
