//! The settings' on-flash record: the current version's encoder and the decoders of every
//! version a module ever wrote (1 … 6), each field range-checked.
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
//! Version 6 (57 bytes) appended a key and the BLE PIN: `[.. version 5 fields .., key_flag,
//! key (16 bytes), ble_pin (u32 LE)]`; `ble_pin` is the HM-10 pairing PIN, 0…999 999, or
//! `u32::MAX` for the factory PIN derived from the chip's unique ID ([`Pin::factory`]).
//!
//! Version 7 (99 bytes, now) keeps that layout — the key is now the link key agreed at bind
//! (spec §12.1; flag 0 = none, the key bytes then all 0) — and appends the binding phrase's
//! derivation and the unauthenticated setting: `[.. version 6 fields .., phrase_flag,
//! phrase_salt (8 bytes), phrase_prs (32 bytes: all 0 with flag 0), plain (0 or 1)]`.
//!
//! Records before version 7 load with their other fields, but not bound (bind ID 0, no
//! models, no key) and without a phrase: their link was bound by the protocol before the key
//! agreement, and version 6's key was the phrase's bare hash, which a recording let a
//! guesser test (issue 30, finding 1). The pilot sets the phrase again and binds.

use telemetry::link::LinkKey;

use super::openlrs::{self, LinkProtocol, OpenLrsSettings};
use super::{
    Band, DEFAULT_INPUT_TIMEOUT_MS, DEFAULT_TELEMETRY_RATIO, INPUT_TIMEOUT_MS, InputProtocol,
    OutputProtocol, RateMode, Role, Settings, TELEMETRY_RATIOS,
};
use crate::hm10::at::Pin;
use crate::ppm::FailsafeOutput;

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

/// Current record version.
pub const RECORD_VERSION: u8 = 7;
/// Record length of the current version.
pub const RECORD_LEN: usize = 99;
/// Record length of version 6 (a key and the PIN, no phrase derivation).
pub const RECORD_V6_LEN: usize = 57;
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
        let (phrase_flag, prs) = match self.phrase_prs {
            Some(prs) => (1, prs),
            None => (0, [0; 32]),
        };
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
        let flags = [phrase_flag];
        let plain = [u8::from(self.plain)];
        let bytes = fields
            .iter()
            .chain(key.iter())
            .chain(pin.iter())
            .chain(flags.iter())
            .chain(self.phrase_salt.iter())
            .chain(prs.iter())
            .chain(plain.iter());
        for (slot, byte) in record.iter_mut().zip(bytes) {
            *slot = *byte;
        }
        record
    }

    /// Parses a record of version 1 … 7; every field is range-checked.
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
            6 => RECORD_V6_LEN,
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
        let (security, phrase) =
            security.split_at(security.len().min(RECORD_V6_LEN - RECORD_V5_LEN));
        let (protocol, openlrs) = decode_link(link)?;
        let (link_key, ble_pin) = match security {
            [flag, tail @ ..] => decode_security(*flag, tail)?,
            [] => (None, None),
        };
        let PhraseTail {
            salt: phrase_salt,
            prs: phrase_prs,
            plain,
        } = decode_phrase(phrase)?;
        // Bound before the key agreement: no link (module doc).
        let bound = version == RECORD_VERSION;
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
            bind_id: if bound {
                u32::from_le_bytes([b0, b1, b2, b3])
            } else {
                0
            },
            input_timeout_ms,
            telemetry_ratio,
            model_match,
            bound_models: if bound { bound_models } else { 0 },
            protocol,
            openlrs,
            link_key: link_key.filter(|_| bound),
            phrase_salt,
            phrase_prs,
            plain,
            ble_pin,
        })
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

/// What version 7's tail holds.
struct PhraseTail {
    salt: [u8; 8],
    prs: Option<[u8; 32]>,
    plain: bool,
}

/// Version 7's tail (empty for older records: no phrase, no salt, authenticated): the phrase
/// flag, the salt, the derivation (all 0 without a phrase) and the unauthenticated setting.
fn decode_phrase(tail: &[u8]) -> Result<PhraseTail, DecodeError> {
    let field = |offset: usize| DecodeError::Field { offset };
    let Some((flag, rest)) = tail.split_first() else {
        return Ok(PhraseTail {
            salt: [0; 8],
            prs: None,
            plain: false,
        });
    };
    let (salt, rest) = rest
        .split_first_chunk::<8>()
        .ok_or(field(RECORD_V6_LEN + 1))?;
    let (prs, rest) = rest
        .split_first_chunk::<32>()
        .ok_or(field(RECORD_V6_LEN + 9))?;
    let prs = match flag {
        0 if prs.iter().all(|b| *b == 0) => None,
        0 => return Err(field(RECORD_V6_LEN + 9)),
        1 => Some(*prs),
        _ => return Err(field(RECORD_V6_LEN)),
    };
    let plain = match rest {
        [0] => false,
        [1] => true,
        _ => return Err(field(RECORD_V6_LEN + 41)),
    };
    Ok(PhraseTail {
        salt: *salt,
        prs,
        plain,
    })
}

#[cfg(test)]
#[path = "record_tests.rs"]
mod tests;
