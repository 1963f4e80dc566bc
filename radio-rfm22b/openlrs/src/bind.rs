//! `struct bind_data` (41 bytes, packed little-endian as on AVR) and the bind exchange: the
//! TX's 42-byte `'b'` packet and the RX's 1-byte `'B'` reply.

use super::channels::ChannelMode;
use super::version::BindingVersion;
use crate::RfmType;

/// Size of the packed `struct bind_data`.
pub const BIND_DATA_LEN: usize = 41;
/// Size of the bind packet: `'b'` plus the struct.
pub const BIND_PACKET_LEN: usize = 1 + BIND_DATA_LEN;
/// `MAXHOPS`: entries in the hop list.
pub const MAX_HOPS: usize = 24;
/// First byte of a bind packet (TX → RX).
pub const BIND_REQUEST: u8 = b'b';
/// The RX's 1-byte bind acknowledgement (RX → TX).
pub const BIND_ACK: u8 = b'B';
/// `DEFAULT_RF_MAGIC`.
pub const DEFAULT_RF_MAGIC: u32 = 0xDEAD_FEED;
/// `DEFAULT_HOPLIST`.
pub const DEFAULT_HOP_LIST: [u8; 6] = [22, 10, 19, 34, 49, 41];
/// Number of modem profiles (`DATARATE_COUNT`).
pub const MODEM_PROFILE_COUNT: u8 = 5;

/// What the downlink carries and what the TX makes of it (`flags & 0x18`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TelemetryMode {
    /// 0x00: no downlink at all.
    Off,
    /// 0x08: transparent serial both ways.
    Passthrough,
    /// 0x10: the TX emits FrSky D hub frames at 9600 baud.
    FrskyHub,
    /// 0x18: the TX emits S.Port frames at 57600 baud.
    SmartPort,
}

/// The 41 bytes both ends share after binding. Field names follow `binding.h`, with units.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BindData {
    /// `BINDING_VERSION` (0x38 or 0x39).
    pub version: u8,
    /// RX UART baud (1..5 select a TX serial input mode; dRonin reads the MSB as `ext_flags`).
    pub serial_baudrate: u32,
    /// Carrier of hop channel 0.
    pub rf_frequency_hz: u32,
    /// The link's 4-byte header; its low byte is XORed with the hop index on air.
    pub rf_magic: u32,
    /// Si4432 TX power code 0..7 (register 0x6D).
    pub rf_power: u8,
    /// Hop step in 10 kHz units (register 0x7A).
    pub rf_channel_spacing: u8,
    /// Channel numbers 1..254, terminated by the first 0.
    pub hop_channels: [u8; MAX_HOPS],
    /// Index into the modem profile table, 0..4.
    pub modem_profile: u8,
    /// Bits 2..0 channel mode, 0x18 telemetry, 0x80 diversity.
    pub flags: u8,
}

/// Bind-data flag: antenna diversity (longer preamble, GPIO2 antenna switch).
pub const FLAG_DIVERSITY: u8 = 0x80;
/// Bind-data flag mask of the telemetry mode.
pub const FLAG_TELEMETRY_MASK: u8 = 0x18;

impl BindData {
    /// `bindInitDefaults()` for a band and a binding version.
    pub const fn defaults(version: BindingVersion, band: RfmType) -> Self {
        let [h0, h1, h2, h3, h4, h5] = DEFAULT_HOP_LIST;
        #[rustfmt::skip]
        let hop_channels = [
            h0, h1, h2, h3, h4, h5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        ];
        Self {
            version: version.byte(),
            serial_baudrate: 115_200,
            rf_frequency_hz: band.default_carrier_frequency_hz(),
            rf_magic: DEFAULT_RF_MAGIC,
            rf_power: 7,
            rf_channel_spacing: 5,
            hop_channels,
            modem_profile: 2,
            // CHANNELS_8 | TELEMETRY_PASSTHRU
            flags: 0x0A,
        }
    }

    /// The struct as OpenLRSng lays it out in memory and on air.
    pub fn to_bytes(&self) -> [u8; BIND_DATA_LEN] {
        let mut out = [0u8; BIND_DATA_LEN];
        let fields = [self.version]
            .into_iter()
            .chain(self.serial_baudrate.to_le_bytes())
            .chain(self.rf_frequency_hz.to_le_bytes())
            .chain(self.rf_magic.to_le_bytes())
            .chain([self.rf_power, self.rf_channel_spacing])
            .chain(self.hop_channels)
            .chain([self.modem_profile, self.flags]);
        for (slot, byte) in out.iter_mut().zip(fields) {
            *slot = byte;
        }
        out
    }

    /// Reads the packed struct back; every 41-byte pattern is a valid struct.
    pub fn from_bytes(bytes: &[u8; BIND_DATA_LEN]) -> Self {
        let [
            version,
            b0,
            b1,
            b2,
            b3,
            f0,
            f1,
            f2,
            f3,
            m0,
            m1,
            m2,
            m3,
            rf_power,
            spacing,
            rest @ ..,
        ] = *bytes;
        let [hops @ .., modem_profile, flags] = rest;
        Self {
            version,
            serial_baudrate: u32::from_le_bytes([b0, b1, b2, b3]),
            rf_frequency_hz: u32::from_le_bytes([f0, f1, f2, f3]),
            rf_magic: u32::from_le_bytes([m0, m1, m2, m3]),
            rf_power,
            rf_channel_spacing: spacing,
            hop_channels: hops,
            modem_profile,
            flags,
        }
    }

    /// The 42-byte bind packet `bindMode()` sends.
    pub fn bind_packet(&self) -> [u8; BIND_PACKET_LEN] {
        let mut out = [0u8; BIND_PACKET_LEN];
        let bytes = core::iter::once(BIND_REQUEST).chain(self.to_bytes());
        for (slot, byte) in out.iter_mut().zip(bytes) {
            *slot = byte;
        }
        out
    }

    /// Number of leading non-zero hop channels (the RX and TX wrap there).
    pub fn hop_count(&self) -> usize {
        self.hop_channels.iter().take_while(|&&ch| ch != 0).count()
    }

    /// The channel mode of `flags & 7`.
    pub fn channel_mode(&self) -> ChannelMode {
        ChannelMode::from_flags(self.flags)
    }

    /// The telemetry mode of `flags & 0x18`.
    pub fn telemetry_mode(&self) -> TelemetryMode {
        match self.flags & FLAG_TELEMETRY_MASK {
            0x00 => TelemetryMode::Off,
            0x08 => TelemetryMode::Passthrough,
            0x10 => TelemetryMode::FrskyHub,
            _ => TelemetryMode::SmartPort,
        }
    }

    /// Whether the RX answers each uplink packet with a 9-byte downlink frame.
    pub fn telemetry_enabled(&self) -> bool {
        self.flags & FLAG_TELEMETRY_MASK != 0
    }

    /// Whether antenna diversity (80-bit preamble) is on.
    pub fn diversity(&self) -> bool {
        self.flags & FLAG_DIVERSITY != 0
    }

    /// The frequency of hop channel number `channel`: `rf_frequency + channel · spacing ·
    /// 10 kHz`, what the Si4432 tunes from 0x75..0x77, 0x79 and 0x7A. In `u64`, so no bind
    /// data can overflow it (the largest is about 4.9 GHz).
    pub fn channel_frequency_hz(&self, channel: u8) -> u64 {
        u64::from(self.rf_frequency_hz)
            + u64::from(channel) * u64::from(self.rf_channel_spacing) * 10_000
    }

    /// The band whose plan holds the carrier (`rf_frequency_hz`), if any.
    pub fn band(&self) -> Option<RfmType> {
        RfmType::containing(u64::from(self.rf_frequency_hz))
    }

    /// Checks what the RX must be able to use before anything is tuned or sent: a known
    /// modem profile, a power code, a non-empty hop list, a carrier inside one band's plan
    /// (`MIN_RFM_FREQUENCY..=MAX_RFM_FREQUENCY`) and every hop of the list (channel ×
    /// spacing above the carrier) inside that same band. OpenLRSng indexes and adds blindly;
    /// dRonin checks only the first three. Without the frequency checks a bind packet that
    /// passes could tune the radio out of its band or overflow a `u32` frequency.
    pub fn validate(&self) -> Result<(), Error> {
        if self.modem_profile >= MODEM_PROFILE_COUNT {
            return Err(Error::ModemProfile(self.modem_profile));
        }
        if self.rf_power > 7 {
            return Err(Error::Power(self.rf_power));
        }
        if self.hop_count() == 0 {
            return Err(Error::NoHopChannels);
        }
        let band = self.band().ok_or(Error::Carrier(self.rf_frequency_hz))?;
        for (index, &channel) in (0u8..).zip(self.hop_channels.iter().take(self.hop_count())) {
            if !band.contains(self.channel_frequency_hz(channel)) {
                return Err(Error::HopOutOfBand { index, channel });
            }
        }
        Ok(())
    }

    /// [`BindData::validate`], and the carrier in `band` (the band the module was built
    /// for: an RFM22B matched for 433 MHz cannot use an 868 MHz link).
    pub fn validate_for(&self, band: RfmType) -> Result<(), Error> {
        self.validate()?;
        match self.band() {
            Some(found) if found == band => Ok(()),
            _ => Err(Error::Carrier(self.rf_frequency_hz)),
        }
    }
}

/// Bind data that cannot be used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// `modem_profile` is not 0..4.
    ModemProfile(u8),
    /// `rf_power` is not 0..7.
    Power(u8),
    /// The hop list starts with 0.
    NoHopChannels,
    /// The carrier is outside the plan of the band (of any band, for
    /// [`BindData::validate`]).
    Carrier(u32),
    /// Hop `index` (channel number `channel`) lies above the carrier's band.
    HopOutOfBand {
        /// Index in the hop list.
        index: u8,
        /// Its channel number.
        channel: u8,
    },
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::ModemProfile(p) => write!(f, "modem profile {p} is not 0..4"),
            Self::Power(p) => write!(f, "rf power {p} is not 0..7"),
            Self::NoHopChannels => write!(f, "hop list is empty"),
            Self::Carrier(hz) => write!(f, "carrier {hz} Hz is outside the band plan"),
            Self::HopOutOfBand { index, channel } => {
                write!(
                    f,
                    "hop {index} (channel {channel}) is outside the band plan"
                )
            }
        }
    }
}

impl core::error::Error for Error {}

/// What the RX makes of a packet received on the bind channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BindReception {
    /// A bind packet for our version: store it and answer [`BIND_ACK`].
    Accepted(BindData),
    /// A bind packet from another OpenLRSng generation; the real RX ignores it too.
    WrongVersion {
        /// The version byte it carried.
        found: u8,
    },
    /// Right version but unusable contents.
    Invalid(Error),
    /// Shorter than 42 bytes (OpenLRSng would read stale FIFO bytes; we refuse).
    TooShort {
        /// Bytes received.
        len: usize,
    },
    /// Not a `'b'` packet (configurator commands and the like).
    NotBind {
        /// The first byte.
        kind: u8,
    },
}

/// Classifies a received bind-channel packet for an RX of `version` built for `band`.
pub fn receive_bind_packet(packet: &[u8], version: BindingVersion, band: RfmType) -> BindReception {
    let Some((&kind, body)) = packet.split_first() else {
        return BindReception::TooShort { len: 0 };
    };
    if kind != BIND_REQUEST {
        return BindReception::NotBind { kind };
    }
    let Some(struct_bytes) = body.first_chunk::<BIND_DATA_LEN>() else {
        return BindReception::TooShort { len: packet.len() };
    };
    let data = BindData::from_bytes(struct_bytes);
    if data.version != version.byte() {
        return BindReception::WrongVersion {
            found: data.version,
        };
    }
    match data.validate_for(band) {
        Ok(()) => BindReception::Accepted(data),
        Err(e) => BindReception::Invalid(e),
    }
}

/// Whether a packet the TX receives in bind mode is the RX's acknowledgement.
pub fn is_bind_ack(packet: &[u8]) -> bool {
    packet.first() == Some(&BIND_ACK)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_packet_matches_reference_bytes() {
        let p = BindData::defaults(BindingVersion::V38, RfmType::Mhz433).bind_packet();
        assert_eq!(&p[..6], &[0x62, 0x38, 0x00, 0xC2, 0x01, 0x00]);
        assert_eq!(&p[6..14], &[0xC0, 0x92, 0xED, 0x19, 0xED, 0xFE, 0xAD, 0xDE]);
        assert_eq!(p[40], 2);
        assert_eq!(p[41], 0x0A);
    }

    #[test]
    fn v38_packet_is_refused_by_v39_rx() {
        let p = BindData::defaults(BindingVersion::V38, RfmType::Mhz433).bind_packet();
        assert_eq!(
            receive_bind_packet(&p, BindingVersion::V39, RfmType::Mhz433),
            BindReception::WrongVersion { found: 0x38 }
        );
        assert!(matches!(
            receive_bind_packet(&p, BindingVersion::V38, RfmType::Mhz433),
            BindReception::Accepted(_)
        ));
        assert_eq!(
            receive_bind_packet(&p[..41], BindingVersion::V38, RfmType::Mhz433),
            BindReception::TooShort { len: 41 }
        );
    }

    #[test]
    fn a_bind_for_another_band_or_leaving_the_band_is_refused() {
        let p = BindData::defaults(BindingVersion::V38, RfmType::Mhz868).bind_packet();
        assert_eq!(
            receive_bind_packet(&p, BindingVersion::V38, RfmType::Mhz433),
            BindReception::Invalid(Error::Carrier(868_000_000))
        );
        let mut data = BindData::defaults(BindingVersion::V38, RfmType::Mhz433);
        // 500 kHz steps: channels 10..49 land at 440..460 MHz, channel 200 at 535 MHz.
        data.rf_channel_spacing = 50;
        data.hop_channels[2] = 200;
        assert_eq!(
            receive_bind_packet(&data.bind_packet(), BindingVersion::V38, RfmType::Mhz433),
            BindReception::Invalid(Error::HopOutOfBand {
                index: 2,
                channel: 200
            })
        );
    }
}
