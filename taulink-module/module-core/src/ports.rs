//! The seams where other crates plug into the module core: the air link (telemetry crate's
//! `link`, driven by the radio driver; [`crate::air::AirLink`]) and the handset telemetry
//! encoders (the `taulink-handset` crate: CRSF, S.Port, FrSky D; [`crate::handset::Handset`]).
//! The core only ever talks to these traits.

use crate::channels::ChannelFrame;

/// When the link sends its uplink packets, on the firmware's µs clock: at `phase_us + k ·
/// period_us`. The CRSF timing frame pulls the radio's channel frames onto this grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AirSchedule {
    /// Slot length (one packet per slot).
    pub period_us: u32,
    /// When one uplink's channels are latched (`telemetry::link::master::uplink_latch_offset_us`
    /// into its slot, the transmitter on): the instant the handset's channel frame must be in
    /// by.
    pub phase_us: u64,
}

/// What the link reports about itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStats {
    /// Packets are arriving from the other end.
    pub connected: bool,
    /// Received signal strength at this module (downlink in the transmitter role), dBm.
    pub rssi_dbm: i16,
    /// Share of expected packets this module received over the last 100 slots, 0…100 %.
    pub link_quality_percent: u8,
    /// What the other end reports about how it hears us, dBm (0: no report yet).
    pub remote_rssi_dbm: i16,
    /// The other end's LQ of our packets, % (`None`: no report yet).
    pub remote_link_quality_percent: Option<u8>,
    /// Wire code of the rate mode (`telemetry::link::RateMode::code`).
    pub rate_code: u8,
    /// The uplink schedule (transmitter role, once the link runs).
    pub schedule: Option<AirSchedule>,
    /// Frames whose authentication tag failed at this end since the link session started
    /// (spec §12.2).
    pub tag_failures: u32,
    /// The power step (0…7) the running TauLink link sends at (`None`: no such link, the
    /// set power applies).
    pub tx_power_step: Option<u8>,
}

/// The link's authentication failures (spec §12.2) as the handset and the phone show them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TagFailures {
    /// Frames whose tag failed at this module since it started.
    pub down: u32,
    /// Frames whose tag failed at the other end (its last report).
    pub up: u32,
    /// Either runs above what noise explains.
    pub alert: bool,
}

/// The air link as the module core sees it.
pub trait LinkPort {
    /// Channels for the next uplink packet (transmitter role), as the handset delivers them.
    fn send_channels(&mut self, channels: &ChannelFrame);
    /// After this long without [`LinkPort::send_channels`] the handset input counts as lost
    /// and the link must stop flying the last channels (it makes the other end fly its
    /// failsafe). The core sets it from the settings when it is built.
    fn set_input_timeout_ms(&mut self, timeout_ms: u16);
    /// The transmit power's maximum step (0…7) and whether it follows the link below it
    /// (`telemetry::link::power`). The core sets it from the settings. Default: ignored (a
    /// link without power control).
    fn set_tx_power(&mut self, max_step: u8, dynamic: bool) {
        let _ = (max_step, dynamic);
    }
    /// Whether the link can take another uplink telemetry record now.
    fn can_send_record(&self) -> bool;
    /// A record for the other end (phone → flight side); only called after
    /// `can_send_record` said yes.
    fn send_record(&mut self, record: &[u8]);
    /// The current statistics.
    fn stats(&self) -> LinkStats;
    /// Start the bind procedure.
    fn start_bind(&mut self);
    /// The link loop stopped (bind, radio failure): forget what only a running link knows.
    fn on_link_stopped(&mut self) {}
    /// The next telemetry record received over the air into `out` (≥ 64 bytes).
    fn take_received_record(&mut self, _out: &mut [u8]) -> Option<usize> {
        None
    }
    /// Channels received over the air since the last call (receiver role).
    fn take_received_channels(&mut self) -> Option<ChannelFrame> {
        None
    }
}

/// What the radio asked of the module over the JR line (CRSF parameter protocol, bind).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HandsetRequest {
    /// Chunk `chunk` of parameter `number`'s description, for `origin`.
    Read {
        /// Who asked (the reply's destination).
        origin: u8,
        /// Parameter number.
        number: u8,
        /// Chunk index.
        chunk: u8,
    },
    /// Set parameter `number` (or step a command).
    Write {
        /// Who wrote.
        origin: u8,
        /// Parameter number.
        number: u8,
        /// Value bytes.
        value: heapless::Vec<u8, { taulink_handset::crsf::params::MAX_WRITE_LEN }>,
    },
    /// The radio's Bind button (CRSF command 0x32 / 0x10 / 0x01).
    Bind,
    /// A frame for the flight controller (CRSF device 0xC8: its parameter reads and
    /// writes, and pings it hears): relayed over the link (`telemetry::crsf_record`).
    Relay {
        /// CRSF frame type.
        frame_type: u8,
        /// CRSF payload (destination, origin, …).
        payload: heapless::Vec<u8, { telemetry::crsf_record::MAX_CRSF_PAYLOAD }>,
    },
}

/// The handset side of the JR line: telemetry encoders (CRSF, S.Port or FrSky D, chosen by
/// the settings) and, with CRSF, the decoder of the radio's frames.
pub trait HandsetOutput {
    /// A telemetry record from the flight side (`crate::records`).
    fn on_telemetry(&mut self, record: &[u8]);
    /// The link's statistics, as often as they change.
    fn on_link_stats(&mut self, stats: &LinkStats);
    /// The module's own supply voltage (the radio battery on JR pin 3), mV.
    fn on_module_battery(&mut self, _millivolts: u16) {}
    /// A keyed link's tag failures at both ends and the alert, as often as they change.
    fn on_tag_failures(&mut self, _failures: TagFailures) {}
    /// Bytes the radio sent on the JR line, the last one received at `now_us`; returns the
    /// newest RC channels they completed.
    fn on_line_bytes(&mut self, _now_us: u64, _bytes: &[u8]) -> Option<ChannelFrame> {
        None
    }
    /// The JR line went idle at `now_us` (end of the radio's burst).
    fn on_line_idle(&mut self, _now_us: u64) -> Option<ChannelFrame> {
        None
    }
    /// What to send on the JR line at `now_us`, written into `out` (≥ 128 bytes); empty =
    /// nothing. The encoder paces itself (S.Port slots, CRSF reply windows).
    fn next_line_bytes<'o>(&mut self, _now_us: u64, _out: &'o mut [u8]) -> &'o [u8] {
        &[]
    }
    /// The oldest request from the radio not yet taken.
    fn take_request(&mut self) -> Option<HandsetRequest> {
        None
    }
    /// Data bytes per parameter chunk the line carries in one reply window.
    fn parameter_chunk_len(&self) -> usize {
        taulink_handset::crsf::params::MAX_CHUNK_DATA
    }
    /// A parameter chunk to send in the next reply window.
    fn send_parameter_chunk(&mut self, _chunk: taulink_handset::crsf::params::ParameterChunk) {}
    /// A CRSF frame the flight controller sent the radio over the link (its DEVICE_INFO, a
    /// parameter chunk), for a coming reply window.
    fn send_relayed_frame(&mut self, _frame_type: u8, _payload: &[u8]) {}
    /// The model ID the radio selected (CRSF model select, 0x32 / 0x10 / 0x05), `None` before
    /// one arrived or on a line that carries none (PPM).
    fn model_id(&self) -> Option<u8> {
        None
    }
}
