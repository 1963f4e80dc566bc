//! The module's settings and their on-flash record.
//!
//! The record is one versioned, fixed-size byte string stored under one key, so a save is
//! a single sequential-storage item write: after a power cut the map holds either the old
//! or the new record (the item CRC rejects a torn write), never a mix of fields.
//!
//! Record layout (version 3, 15 bytes, and versions 4 to 6 below; input 0 PPM, 1 CRSF 400 kBd, 2 CRSF 115 200 Bd,
//! 3 CRSF 921 600 Bd;
//! failsafe 0 hold last, 1 stop pulses; rate = `telemetry::link::RateMode::code`):
//! `[4, role, rate, input, output, band, tx_power, failsafe, bind_id (u32 LE),
//! input_timeout_ms (u16 LE), telemetry_ratio, key_flag, key (16 bytes), ble_pin (u32 LE)]`.
//! The key is the link key derived from the binding phrase (spec §12; flag 0 = no phrase, the
//! key bytes then all 0; the phrase itself is never stored); `ble_pin` is the HM-10 pairing
//! PIN, 0…999 999, or `u32::MAX` for the factory PIN derived from the chip's unique ID
//! ([`Pin::factory`]). The rate byte is the link's own rate mode,
//! the one vocabulary the handset's "Packet Rate" shows. Band 0 is the 70 cm amateur plan
//! (factory), 1 EU 868, 2 US 915, 3 (version 3 only) the 433.05–434.79 MHz ISM plan.
//!
//! Older records still load, every stored field with its old meaning: version 3 (15 bytes,
//! up to the telemetry ratio) has no phrase and the factory PIN; version 2 (14 bytes,
//! no telemetry ratio) and version 1 (12 bytes, no input timeout either) stored the air rate
//! in Tau Labs' bit-rate vocabulary, which maps to the link mode that rate ran as (4800,
//! 9600 and 19 200 bit/s → L50, 57 600 → M100, 125 000 → F250); a missing field takes its
//! default. Every byte is checked on decode; an unknown value is an error, never a guess.
//!
//! Version 4 (24 bytes) appends model match (spec §12.6): `[…version 3 fields, model_match
//! (0 off, 1 on), bound_models (u64 LE: bit m set = a receiver was bound under radio model
//! m)]`; older records load with model match off and no models bound.
//!
//! Version 5 (36 bytes) appends the link protocol and the OpenLRSng bind parameters
//! (`settings::openlrs`): `[.. version 4 fields .., protocol (0 TauLink, 1 OpenLRSng 3.8,
//! 2 OpenLRSng 3.9), olrs_profile, olrs_channel_mode, olrs_telemetry, olrs_frequency_hz
//! (u32 LE, 0 = band default), olrs_hop_seed (u32 LE)]`. Older records load as TauLink with
//! OpenLRSng's factory parameters.
//!
//! Version 6 (57 bytes) appends the link key and the BLE PIN: `[.. version 5 fields ..,
//! key_flag, key (16 bytes), ble_pin (u32 LE)]`. The key is the link key derived from the
//! binding phrase (spec §12; flag 0 = no phrase, the key bytes then all 0; the phrase itself
//! is never stored); `ble_pin` is the HM-10 pairing PIN, 0…999 999, or `u32::MAX` for the
//! factory PIN derived from the chip's unique ID ([`Pin::factory`]). Older records load with
//! no phrase and the factory PIN.

pub mod openlrs;
pub mod store;
pub mod text;

pub use openlrs::{LinkProtocol, OpenLrsError, OpenLrsSettings};
pub use store::{SettingsStore, StoreError};
pub use text::TextError;

use telemetry::link::LinkKey;

use crate::hm10::at::Pin;
use crate::ppm::FailsafeOutput;

/// Which end of the link the module is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Role {
    /// JR-bay transmitter: handset in, telemetry out.
    Transmitter,
    /// Receiver: link in, PPM out.
    Receiver,
}

/// The air packet rate: the link's own rate modes (L50 … F500).
pub use telemetry::link::RateMode;

/// The link mode a version-1/2 record's bit-rate code ran as: the three slow OpenLRSng-style
/// rates shared the link's 19.2 kbit/s L50, 57 600 bit/s was M100, 125 000 bit/s F250.
pub const fn rate_from_old_code(code: u8) -> Option<RateMode> {
    match code {
        0..=2 => Some(RateMode::L50),
        3 => Some(RateMode::M100),
        4 => Some(RateMode::F250),
        _ => None,
    }
}

/// Where the channels come from in the transmitter role.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InputProtocol {
    /// PPM on JR pin 1.
    Ppm,
    /// CRSF on JR pin 5 (half duplex) at 400 kBd, EdgeTX's default.
    Crsf,
    /// CRSF at 115 200 Bd, for radios or cables that cannot run 400 kBd.
    Crsf115200,
    /// CRSF at 921 600 Bd (EdgeTX "921K"); the nRF52840 UARTE runs it at 941 176 Bd
    /// (`handset::uarte_baudrate`).
    Crsf921600,
}

impl InputProtocol {
    /// CRSF at any rate.
    pub const fn is_crsf(self) -> bool {
        self.crsf_baud().is_some()
    }

    /// The CRSF line rate, `None` for PPM. EdgeTX's 1.87 MBd and faster are beyond the
    /// nRF52840 UARTE's 1 MBd and not offered.
    pub const fn crsf_baud(self) -> Option<u32> {
        match self {
            InputProtocol::Ppm => None,
            InputProtocol::Crsf => Some(400_000),
            InputProtocol::Crsf115200 => Some(115_200),
            InputProtocol::Crsf921600 => Some(921_600),
        }
    }
}

/// What goes back to the handset on JR pin 5 (transmitter role).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OutputProtocol {
    /// Nothing.
    Off,
    /// CRSF telemetry frames (with CRSF input).
    Crsf,
    /// FrSky S.Port frames pushed unpolled at 57 600 Bd (how a PPM module's telemetry reaches
    /// EdgeTX ≥ 2.11 and OpenTX 2.2/2.3; see `handset`).
    SPort,
    /// FrSky D hub frames at 9600 Bd (older radios).
    FrskyHub,
}

/// Frequency band plan: the link's own type (`telemetry::link::Band` says what each means
/// legally); the record stores its [`Band::code`].
pub use telemetry::link::Band;

/// Everything the module remembers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// Transmitter or receiver.
    pub role: Role,
    /// Air packet rate (the link's rate mode).
    pub rate: RateMode,
    /// Handset input.
    pub input: InputProtocol,
    /// Handset telemetry output.
    pub output: OutputProtocol,
    /// RF band.
    pub band: Band,
    /// RFM22B power step 0…7 (register 0x6D bits 2..0: +1, +2, +5, +8, +11, +14, +17, +20 dBm,
    /// Si4432 datasheet, register 6Dh).
    pub tx_power: u8,
    /// Failsafe behaviour of the PPM output (receiver role).
    pub failsafe: FailsafeOutput,
    /// Identity shared with the bound peer.
    pub bind_id: u32,
    /// Transmitter role: the handset input (PPM or CRSF) counts as lost after this long
    /// without a frame, ms ([`INPUT_TIMEOUT_MS`]); the link then tells the flight side to
    /// fly its failsafe instead of stale sticks.
    pub input_timeout_ms: u16,
    /// One link slot in this many is a downlink (telemetry) slot: a power of two,
    /// [`TELEMETRY_RATIOS`].
    pub telemetry_ratio: u8,
    /// Model match (ExpressLRS-style, spec §12.6): the link's identity is mixed with the
    /// model ID the radio selects (CRSF model select), so a receiver bound under one model
    /// never flies from another; off, every model flies the receivers bound without it.
    pub model_match: bool,
    /// The radio models (IDs 0…63, bit m) a receiver was bound under with model match on,
    /// since the bind ID last changed: the handset's "Model" row says "mismatch" for any
    /// other.
    pub bound_models: u64,
    /// The air protocol: TauLink (factory) or OpenLRSng 3.8 / 3.9 (unauthenticated).
    pub protocol: LinkProtocol,
    /// The OpenLRSng transmitter's bind parameters (used when `protocol` is OpenLRSng).
    pub openlrs: OpenLrsSettings,
    /// The link key derived from the binding phrase (spec §12); `None`: no phrase, the link
    /// runs unauthenticated. Set with `set_text("phrase", …)`.
    pub link_key: Option<LinkKey>,
    /// The HM-10 pairing PIN; `None`: the factory PIN derived from the chip's unique ID
    /// ([`Pin::factory`]), never the HM-10's own 000000.
    pub ble_pin: Option<Pin>,
}

/// Radio model IDs model match keeps track of (EdgeTX's receiver numbers 0…63).
pub const MODEL_IDS: u8 = 64;

impl Settings {
    /// Whether a receiver was bound under radio model `model_id` with model match on.
    pub fn model_bound(&self, model_id: u8) -> bool {
        model_id < MODEL_IDS && self.bound_models & (1u64 << model_id) != 0
    }
}

/// The telemetry ratios the link takes (`telemetry::frame::valid_telemetry_ratio`).
pub const TELEMETRY_RATIOS: [u8; 7] = [2, 4, 8, 16, 32, 64, 128];
/// Factory telemetry ratio: one slot in 4.
pub const DEFAULT_TELEMETRY_RATIO: u8 = 4;

/// Range and default of [`Settings::input_timeout_ms`]: never shorter than a few frames of
/// the slowest input (PPM 22.5 ms, CRSF at 50 Hz), never so long that stale sticks fly for
/// seconds.
pub const INPUT_TIMEOUT_MS: core::ops::RangeInclusive<u16> = 100..=2_000;
/// Factory input timeout: the flight side is in failsafe within 1 s of the input stopping.
pub const DEFAULT_INPUT_TIMEOUT_MS: u16 = 500;

impl Default for Settings {
    fn default() -> Self {
        Self {
            role: Role::Transmitter,
            rate: RateMode::L50,
            input: InputProtocol::Ppm,
            output: OutputProtocol::SPort,
            band: Band::Mhz433,
            tx_power: 7,
            // Holding the last values would hold the throttle on a lost link.
            failsafe: FailsafeOutput::StopPulses,
            bind_id: 0,
            input_timeout_ms: DEFAULT_INPUT_TIMEOUT_MS,
            telemetry_ratio: DEFAULT_TELEMETRY_RATIO,
            model_match: false,
            bound_models: 0,
            protocol: LinkProtocol::TauLink,
            openlrs: OpenLrsSettings::default(),
            link_key: None,
            ble_pin: None,
        }
    }
}

/// Current record version.
pub const RECORD_VERSION: u8 = 6;
/// Record length of the current version.
pub const RECORD_LEN: usize = 57;
/// Record length of version 5 (link protocol, no phrase or PIN).
pub const RECORD_V5_LEN: usize = 36;
/// Record length of version 4 (model match, no link protocol).
pub const RECORD_V4_LEN: usize = 24;
/// Record length of version 3 (no model match).
pub const RECORD_V3_LEN: usize = 15;
/// The stored `ble_pin` that means "the factory PIN".
const FACTORY_PIN: u32 = u32::MAX;
/// Record length of version 2 (bit-rate codes, no telemetry ratio).
pub const RECORD_V2_LEN: usize = 14;
/// Record length of version 1 (bit-rate codes, no input timeout).
pub const RECORD_V1_LEN: usize = 12;

/// Why a record does not decode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// Wrong length for its version.
    Length {
        /// Bytes found.
        found: usize,
    },
    /// Unknown record version.
    Version {
        /// Version found.
        found: u8,
    },
    /// A field holds a value no writer of its version produces.
    Field {
        /// Byte offset of the field.
        offset: usize,
    },
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Length { found } => write!(f, "settings record of {found} bytes"),
            Self::Version { found } => write!(f, "settings record version {found}"),
            Self::Field { offset } => write!(f, "bad settings field at byte {offset}"),
        }
    }
}

impl core::error::Error for DecodeError {}

impl Settings {
    /// The current (version 6) record.
    pub fn to_record(&self) -> [u8; RECORD_LEN] {
        let [b0, b1, b2, b3] = self.bind_id.to_le_bytes();
        let [t0, t1] = self.input_timeout_ms.to_le_bytes();
        let [m0, m1, m2, m3, m4, m5, m6, m7] = self.bound_models.to_le_bytes();
        let [f0, f1, f2, f3] = self.openlrs.frequency_hz.to_le_bytes();
        let [s0, s1, s2, s3] = self.openlrs.hop_seed.to_le_bytes();
        let (flag, key) = match self.link_key {
            Some(key) => (1, key.to_bytes()),
            None => (0, [0; 16]),
        };
        let pin = self.ble_pin.map_or(FACTORY_PIN, Pin::value).to_le_bytes();
        let mut record = [0u8; RECORD_LEN];
        let fields = [
            RECORD_VERSION,
            self.role as u8,
            self.rate.code(),
            self.input as u8,
            self.output as u8,
            self.band.code(),
            self.tx_power,
            self.failsafe as u8,
            b0,
            b1,
            b2,
            b3,
            t0,
            t1,
            self.telemetry_ratio,
            u8::from(self.model_match),
            m0,
            m1,
            m2,
            m3,
            m4,
            m5,
            m6,
            m7,
            self.protocol.code(),
            self.openlrs.profile,
            self.openlrs.channel_mode,
            u8::from(self.openlrs.telemetry),
            f0,
            f1,
            f2,
            f3,
            s0,
            s1,
            s2,
            s3,
            flag,
        ];
        let bytes = fields.iter().chain(key.iter()).chain(pin.iter());
        for (slot, byte) in record.iter_mut().zip(bytes) {
            *slot = *byte;
        }
        record
    }

    /// Parses a record of version 1 … 6; every field is range-checked.
    pub fn from_record(record: &[u8]) -> Result<Self, DecodeError> {
        let Some(&version) = record.first() else {
            return Err(DecodeError::Length { found: 0 });
        };
        let wrong_length = DecodeError::Length {
            found: record.len(),
        };
        let expected = match version {
            1 => RECORD_V1_LEN,
            2 => RECORD_V2_LEN,
            3 => RECORD_V3_LEN,
            4 => RECORD_V4_LEN,
            5 => RECORD_V5_LEN,
            RECORD_VERSION => RECORD_LEN,
            found => return Err(DecodeError::Version { found }),
        };
        if record.len() != expected {
            return Err(wrong_length);
        }
        let (common, rest) = record
            .split_first_chunk::<RECORD_V1_LEN>()
            .ok_or(wrong_length)?;
        let input_timeout_ms = match rest {
            [t0, t1, ..] => {
                let timeout = u16::from_le_bytes([*t0, *t1]);
                if !INPUT_TIMEOUT_MS.contains(&timeout) {
                    return Err(DecodeError::Field {
                        offset: RECORD_V1_LEN,
                    });
                }
                timeout
            }
            _ => DEFAULT_INPUT_TIMEOUT_MS,
        };
        let (rest, tail) = rest.split_at(rest.len().min(RECORD_V3_LEN - RECORD_V1_LEN));
        let (models, link) = tail.split_at(tail.len().min(RECORD_V4_LEN - RECORD_V3_LEN));
        let (link, security) = link.split_at(link.len().min(RECORD_V5_LEN - RECORD_V4_LEN));
        let (protocol, openlrs) = decode_link(link)?;
        let (link_key, ble_pin) = match security {
            [flag, tail @ ..] => decode_security(*flag, tail)?,
            [] => (None, None),
        };
        let telemetry_ratio = match rest {
            [_, _, ratio, ..] if TELEMETRY_RATIOS.contains(ratio) => *ratio,
            [_, _, _, ..] => {
                return Err(DecodeError::Field {
                    offset: RECORD_V2_LEN,
                });
            }
            _ => DEFAULT_TELEMETRY_RATIO,
        };
        let (model_match, bound_models) = match models {
            [on @ (0 | 1), models @ ..] => {
                let models: [u8; 8] = models.try_into().map_err(|_| wrong_length)?;
                (*on == 1, u64::from_le_bytes(models))
            }
            [_, ..] => {
                return Err(DecodeError::Field {
                    offset: RECORD_V3_LEN,
                });
            }
            [] => (false, 0),
        };
        // Rate codes, the fastest CRSF input and the ISM plan are version 3's vocabulary.
        let current = version >= 3;
        let [
            _,
            role,
            rate,
            input,
            output,
            band,
            tx_power,
            failsafe,
            b0,
            b1,
            b2,
            b3,
        ] = *common;
        let field = |offset: usize| DecodeError::Field { offset };
        Ok(Self {
            role: match role {
                0 => Role::Transmitter,
                1 => Role::Receiver,
                _ => return Err(field(1)),
            },
            rate: if current {
                RateMode::from_code(rate)
            } else {
                rate_from_old_code(rate)
            }
            .ok_or(field(2))?,
            input: match input {
                0 => InputProtocol::Ppm,
                1 => InputProtocol::Crsf,
                2 => InputProtocol::Crsf115200,
                3 if current => InputProtocol::Crsf921600,
                _ => return Err(field(3)),
            },
            output: match output {
                0 => OutputProtocol::Off,
                1 => OutputProtocol::Crsf,
                2 => OutputProtocol::SPort,
                3 => OutputProtocol::FrskyHub,
                _ => return Err(field(4)),
            },
            band: match Band::from_code(band) {
                // The ISM plan came with version 3.
                Some(Band::Ism433) if !current => return Err(field(5)),
                Some(band) => band,
                None => return Err(field(5)),
            },
            tx_power: if tx_power <= 7 {
                tx_power
            } else {
                return Err(field(6));
            },
            failsafe: match failsafe {
                0 => FailsafeOutput::HoldLast,
                1 => FailsafeOutput::StopPulses,
                _ => return Err(field(7)),
            },
            bind_id: u32::from_le_bytes([b0, b1, b2, b3]),
            input_timeout_ms,
            telemetry_ratio,
            model_match,
            bound_models,
            protocol,
            openlrs,
            link_key,
            ble_pin,
        })
    }

    /// Whether the whole set runs (`openlrs::check`: an OpenLRSng link's carrier and hops
    /// inside the band plan, transmitter role). Every settings path checks it before a
    /// change sticks.
    pub fn validate(&self) -> Result<(), OpenLrsError> {
        openlrs::check(self)
    }
}

/// The version-5 tail (empty for older records: TauLink, OpenLRSng factory parameters).
fn decode_link(link: &[u8]) -> Result<(LinkProtocol, OpenLrsSettings), DecodeError> {
    let [
        protocol,
        profile,
        mode,
        telemetry,
        f0,
        f1,
        f2,
        f3,
        s0,
        s1,
        s2,
        s3,
    ] = *link
    else {
        return Ok((LinkProtocol::TauLink, OpenLrsSettings::default()));
    };
    let field = |offset: usize| DecodeError::Field { offset };
    let protocol = LinkProtocol::from_code(protocol).ok_or(field(RECORD_V4_LEN))?;
    if profile >= ::openlrs::bind::MODEM_PROFILE_COUNT {
        return Err(field(RECORD_V4_LEN + 1));
    }
    if !openlrs::CHANNEL_MODES.contains(&mode) {
        return Err(field(RECORD_V4_LEN + 2));
    }
    let telemetry = match telemetry {
        0 => false,
        1 => true,
        _ => return Err(field(RECORD_V4_LEN + 3)),
    };
    let frequency_hz = u32::from_le_bytes([f0, f1, f2, f3]);
    if !openlrs::carrier_in_range(frequency_hz) {
        return Err(field(RECORD_V4_LEN + 4));
    }
    Ok((
        protocol,
        OpenLrsSettings {
            frequency_hz,
            profile,
            channel_mode: mode,
            telemetry,
            hop_seed: u32::from_le_bytes([s0, s1, s2, s3]),
        },
    ))
}

/// Version 6's key flag (at [`RECORD_V5_LEN`]) and what follows it: the key bytes (all 0
/// without a key, so every byte has one meaning) and the PIN.
fn decode_security(flag: u8, tail: &[u8]) -> Result<(Option<LinkKey>, Option<Pin>), DecodeError> {
    let field = |offset: usize| DecodeError::Field { offset };
    let (key, pin) = tail.split_first_chunk::<16>().ok_or(DecodeError::Length {
        found: RECORD_V5_LEN + 1 + tail.len(),
    })?;
    let pin: [u8; 4] = pin.try_into().map_err(|_| DecodeError::Length {
        found: RECORD_V5_LEN + 1 + tail.len(),
    })?;
    let link_key = match flag {
        0 if key.iter().all(|b| *b == 0) => None,
        0 => return Err(field(RECORD_V5_LEN + 1)),
        1 => Some(LinkKey::from_bytes(*key)),
        _ => return Err(field(RECORD_V5_LEN)),
    };
    let ble_pin = match u32::from_le_bytes(pin) {
        FACTORY_PIN => None,
        value => Some(Pin::new(value).ok_or(field(RECORD_V5_LEN + 17))?),
    };
    Ok((link_key, ble_pin))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_round_trip_and_layout() {
        let settings = Settings {
            role: Role::Receiver,
            rate: RateMode::F500,
            input: InputProtocol::Crsf,
            output: OutputProtocol::FrskyHub,
            band: Band::Mhz915,
            tx_power: 5,
            failsafe: FailsafeOutput::StopPulses,
            bind_id: 0xDEAD_BEEF,
            input_timeout_ms: 750,
            telemetry_ratio: 16,
            model_match: true,
            bound_models: (1 << 63) | (1 << 3),
            protocol: LinkProtocol::OpenLrs39,
            openlrs: OpenLrsSettings {
                frequency_hz: 0x3456_7890,
                profile: 4,
                channel_mode: 6,
                telemetry: false,
                hop_seed: 0xCAFE_F00D,
            },
            link_key: Some(LinkKey::from_bytes(core::array::from_fn(|i| {
                0xA0 + i as u8
            }))),
            ble_pin: Pin::new(42_917),
        };
        let record = settings.to_record();
        assert_eq!(
            record[..RECORD_V5_LEN],
            [
                6, 1, 3, 1, 3, 2, 5, 1, 0xEF, 0xBE, 0xAD, 0xDE, 0xEE, 0x02, 16, 1, 0x08, 0, 0, 0,
                0, 0, 0, 0x80, 2, 4, 6, 0, 0x90, 0x78, 0x56, 0x34, 0x0D, 0xF0, 0xFE, 0xCA
            ]
        );
        assert!(settings.model_bound(3) && settings.model_bound(63));
        assert!(!settings.model_bound(4) && !settings.model_bound(64));
        assert_eq!(
            record[RECORD_V5_LEN..RECORD_V5_LEN + 1 + 16],
            core::array::from_fn::<u8, 17, _>(|i| if i == 0 { 1 } else { 0xA0 + i as u8 - 1 })
        );
        assert_eq!(record[RECORD_V5_LEN + 17..], 42_917u32.to_le_bytes());
        assert_eq!(Settings::from_record(&record), Ok(settings));
        assert_eq!(
            Settings::from_record(&Settings::default().to_record()),
            Ok(Settings::default())
        );
        // Every link rate mode is stored as its own code.
        for rate in RateMode::ALL {
            let s = Settings { rate, ..settings };
            assert_eq!(s.to_record()[2], rate.code());
            assert_eq!(Settings::from_record(&s.to_record()), Ok(s));
        }
        // The slower CRSF rate is input code 2 (older records never hold it).
        let slow = Settings {
            input: InputProtocol::Crsf115200,
            ..settings
        };
        assert_eq!(slow.to_record()[3], 2);
        assert_eq!(Settings::from_record(&slow.to_record()), Ok(slow));
        let fast = Settings {
            input: InputProtocol::Crsf921600,
            ..settings
        };
        assert_eq!(fast.to_record()[3], 3);
        assert_eq!(Settings::from_record(&fast.to_record()), Ok(fast));
    }

    #[test]
    fn bad_records_are_errors() {
        assert_eq!(
            Settings::from_record(&[]),
            Err(DecodeError::Length { found: 0 })
        );
        assert_eq!(
            Settings::from_record(&[7; 57]),
            Err(DecodeError::Version { found: 7 })
        );
        assert_eq!(
            Settings::from_record(&[6; 36]),
            Err(DecodeError::Length { found: 36 })
        );
        assert_eq!(
            Settings::from_record(&[5; 24]),
            Err(DecodeError::Length { found: 24 })
        );
        assert_eq!(
            Settings::from_record(&[4; 15]),
            Err(DecodeError::Length { found: 15 })
        );
        // Model match is 0 or 1.
        let mut record = Settings::default().to_record();
        record[RECORD_V3_LEN] = 2;
        assert_eq!(
            Settings::from_record(&record),
            Err(DecodeError::Field {
                offset: RECORD_V3_LEN
            })
        );
        // A version 3 record loads with model match off and no models bound.
        let mut v3 = [0u8; RECORD_V3_LEN];
        v3.copy_from_slice(&Settings::default().to_record()[..RECORD_V3_LEN]);
        v3[0] = 3;
        assert_eq!(Settings::from_record(&v3), Ok(Settings::default()));
        assert_eq!(
            Settings::from_record(&[3; 14]),
            Err(DecodeError::Length { found: 14 })
        );
        assert_eq!(
            Settings::from_record(&[2; 12]),
            Err(DecodeError::Length { found: 12 })
        );
        assert_eq!(
            Settings::from_record(&[1; 11]),
            Err(DecodeError::Length { found: 11 })
        );
        let mut record = Settings::default().to_record();
        record[6] = 8;
        assert_eq!(
            Settings::from_record(&record),
            Err(DecodeError::Field { offset: 6 })
        );
        record[6] = 7;
        // Rate code 4 was 125 000 bit/s in version 2; in version 3 it is F700, and there is
        // no mode 5.
        record[2] = 4;
        assert_eq!(Settings::from_record(&record).unwrap().rate, RateMode::F700);
        record[2] = 5;
        assert_eq!(
            Settings::from_record(&record),
            Err(DecodeError::Field { offset: 2 })
        );
        record[2] = 2;
        for (timeout, ok) in [(99u16, false), (100, true), (2_000, true), (2_001, false)] {
            record[12..14].copy_from_slice(&timeout.to_le_bytes());
            assert_eq!(
                Settings::from_record(&record).map(|s| s.input_timeout_ms),
                if ok {
                    Ok(timeout)
                } else {
                    Err(DecodeError::Field { offset: 12 })
                }
            );
        }
        record[12..14].copy_from_slice(&500u16.to_le_bytes());
        for (ratio, ok) in [(0u8, false), (1, false), (2, true), (3, false), (128, true)] {
            record[14] = ratio;
            assert_eq!(
                Settings::from_record(&record).map(|s| s.telemetry_ratio),
                if ok {
                    Ok(ratio)
                } else {
                    Err(DecodeError::Field { offset: 14 })
                }
            );
        }
    }

    #[test]
    fn version_3_records_load_as_taulink_and_the_link_tail_is_checked() {
        // A version-3 record as the previous firmware wrote it.
        let v3 = [
            3, 0, 3, 1, 2, 1, 5, 1, 0xEF, 0xBE, 0xAD, 0xDE, 0xEE, 0x02, 16,
        ];
        let settings = Settings::from_record(&v3).unwrap();
        assert_eq!(settings.protocol, LinkProtocol::TauLink);
        assert_eq!(settings.openlrs, OpenLrsSettings::default());
        assert_eq!(
            (settings.rate, settings.band),
            (RateMode::F500, Band::Mhz868)
        );
        // Re-saved, every version-3 field keeps its byte.
        assert_eq!(settings.to_record()[1..RECORD_V3_LEN], v3[1..]);
        let mut record = Settings {
            protocol: LinkProtocol::OpenLrs38,
            ..Settings::default()
        }
        .to_record();
        assert_eq!(record[RECORD_V4_LEN..RECORD_V4_LEN + 4], [1, 2, 2, 1]);
        for (offset, bad) in [(24, 3u8), (25, 5), (26, 0), (26, 7), (27, 2)] {
            let mut r = record;
            r[offset] = bad;
            assert_eq!(
                Settings::from_record(&r),
                Err(DecodeError::Field { offset }),
                "byte {offset} = {bad}"
            );
        }
        // A carrier outside every OpenLRSng module range (1 GHz) is refused; 0 (band
        // default) and 868 MHz load.
        for (hz, ok) in [(1_000_000_000u32, false), (0, true), (868_000_000, true)] {
            record[28..32].copy_from_slice(&hz.to_le_bytes());
            assert_eq!(Settings::from_record(&record).is_ok(), ok, "{hz}");
        }
    }

    #[test]
    fn the_ism_433_plan_is_band_3_in_version_3_only() {
        let ism = Settings {
            band: Band::Ism433,
            ..Settings::default()
        };
        assert_eq!(ism.to_record()[5], 3);
        assert_eq!(Settings::from_record(&ism.to_record()), Ok(ism));
        assert_eq!(
            Settings::default().band,
            Band::Mhz433,
            "factory: the amateur plan"
        );
        let v2 = [2, 0, 2, 0, 2, 3, 7, 1, 1, 0, 0, 0, 0xF4, 0x01];
        assert_eq!(
            Settings::from_record(&v2),
            Err(DecodeError::Field { offset: 5 })
        );
    }

    #[test]
    fn old_bit_rates_map_to_the_link_mode_they_ran_as() {
        // Version 2 records (14 bytes) in the bit-rate vocabulary: 4800/9600/19 200 → L50,
        // 57 600 → M100, 125 000 → F250; the ratio is the factory one.
        let v2 = |rate: u8| {
            [
                2, 0, rate, 0, 2, 0, 7, 1, 0x78, 0x56, 0x34, 0x12, 0xF4, 0x01,
            ]
        };
        for (code, mode) in [
            (0, RateMode::L50),
            (1, RateMode::L50),
            (2, RateMode::L50),
            (3, RateMode::M100),
            (4, RateMode::F250),
        ] {
            let settings = Settings::from_record(&v2(code)).unwrap();
            assert_eq!(settings.rate, mode, "v2 code {code}");
            assert_eq!(settings.telemetry_ratio, DEFAULT_TELEMETRY_RATIO);
            assert_eq!(settings.input_timeout_ms, 500);
            assert_eq!(settings.bind_id, 0x1234_5678);
            // Re-saved as the current version, the same settings come back.
            assert_eq!(settings.to_record()[0], RECORD_VERSION);
            assert_eq!(Settings::from_record(&settings.to_record()), Ok(settings));
        }
        assert_eq!(
            Settings::from_record(&v2(5)),
            Err(DecodeError::Field { offset: 2 })
        );
    }

    #[test]
    fn the_factory_failsafe_stops_pulses_and_old_records_keep_their_meaning() {
        assert_eq!(Settings::default().failsafe, FailsafeOutput::StopPulses);
        assert_eq!(Settings::default().input_timeout_ms, 500);
        assert_eq!(Settings::default().rate, RateMode::L50);
        // Version-1 records as the first firmware wrote them: hold last (its default) stays
        // hold last, stop pulses stays stop pulses, and the input timeout is the default.
        let v1_hold = [1, 0, 2, 0, 2, 0, 7, 0, 0x78, 0x56, 0x34, 0x12];
        let settings = Settings::from_record(&v1_hold).unwrap();
        assert_eq!(settings.failsafe, FailsafeOutput::HoldLast);
        assert_eq!(settings.bind_id, 0x1234_5678);
        assert_eq!(settings.rate, RateMode::L50, "19 200 bit/s ran as L50");
        assert_eq!(settings.input_timeout_ms, DEFAULT_INPUT_TIMEOUT_MS);
        let mut v1_stop = v1_hold;
        v1_stop[7] = 1;
        assert_eq!(
            Settings::from_record(&v1_stop).unwrap().failsafe,
            FailsafeOutput::StopPulses
        );
        // Re-saved, they become the current version with the same values.
        let upgraded = settings.to_record();
        assert_eq!(upgraded[0], RECORD_VERSION);
        assert_eq!(Settings::from_record(&upgraded), Ok(settings));
    }

    #[test]
    fn a_version_3_record_loads_with_no_phrase_and_the_factory_pin() {
        let v3 = [
            3, 1, 3, 1, 3, 3, 5, 1, 0xEF, 0xBE, 0xAD, 0xDE, 0xEE, 0x02, 16,
        ];
        let settings = Settings::from_record(&v3).unwrap();
        assert_eq!(settings.link_key, None);
        assert_eq!(settings.ble_pin, None);
        assert_eq!(
            (
                settings.rate,
                settings.band,
                settings.bind_id,
                settings.telemetry_ratio
            ),
            (RateMode::F500, Band::Ism433, 0xDEAD_BEEF, 16)
        );
        let upgraded = settings.to_record();
        assert_eq!(upgraded[0], RECORD_VERSION);
        assert_eq!(upgraded[1..15], v3[1..]);
        assert_eq!(Settings::from_record(&upgraded), Ok(settings));
    }

    #[test]
    fn the_phrase_and_pin_fields_take_only_what_a_writer_produces() {
        let keyed = Settings {
            link_key: Some(LinkKey::from_phrase("a")),
            ..Settings::default()
        };
        let mut record = keyed.to_record();
        assert_eq!(Settings::from_record(&record), Ok(keyed));
        let (flag, pin) = (RECORD_V5_LEN, RECORD_V5_LEN + 17);
        record[flag] = 2;
        assert_eq!(
            Settings::from_record(&record),
            Err(DecodeError::Field { offset: flag })
        );
        // No key, yet key bytes: not a record any writer makes.
        record[flag] = 0;
        assert_eq!(
            Settings::from_record(&record),
            Err(DecodeError::Field { offset: flag + 1 })
        );
        let mut record = Settings::default().to_record();
        assert_eq!(record[pin..], [0xFF; 4], "the factory PIN");
        record[pin..].copy_from_slice(&1_000_000u32.to_le_bytes());
        assert_eq!(
            Settings::from_record(&record),
            Err(DecodeError::Field { offset: pin })
        );
        record[pin..].copy_from_slice(&0u32.to_le_bytes());
        assert_eq!(
            Settings::from_record(&record).map(|s| s.ble_pin),
            Ok(Pin::new(0)),
            "000000 set on purpose stays possible"
        );
    }

    proptest::proptest! {
        #[test]
        fn any_bytes_decode_or_error(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..64)) {
            if let Ok(settings) = Settings::from_record(&bytes) {
                // A current record re-encodes to itself; an older one to its upgrade, which
                // decodes to the same settings.
                let record = settings.to_record();
                if bytes.first() == Some(&RECORD_VERSION) {
                    proptest::prop_assert_eq!(&record[..], &bytes[..]);
                } else {
                    proptest::prop_assert_eq!(Settings::from_record(&record), Ok(settings));
                    proptest::prop_assert_eq!(&record[3..RECORD_V1_LEN], &bytes[3..RECORD_V1_LEN]);
                }
            }
        }
    }
}
