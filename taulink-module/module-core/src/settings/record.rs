//! The settings' on-flash record: the current version's encoder and the decoders of every
//! version a module ever wrote (1 … 7), each field range-checked.
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
//! Version 7 (99 bytes) keeps that layout — the key is now the link key agreed at bind
//! (spec §12.1; flag 0 = none, the key bytes then all 0) — and appends the binding phrase's
//! derivation and the unauthenticated setting: `[.. version 6 fields .., phrase_flag,
//! phrase_salt (8 bytes), phrase_prs (32 bytes: all 0 with flag 0), plain (0 or 1)]`.
//!
//! Version 8 (100 bytes, now) appends dynamic transmit power: `[.. version 7 fields ..,
//! dynamic_power (0 off, 1 on)]`; a version-7 record loads with it on (the factory value),
//! its link still bound.
//!
//! Records before version 7 load with their other fields, but not bound (bind ID 0, no
//! models, no key) and without a phrase: their link was bound by the protocol before the key
//! agreement, and version 6's key was the phrase's bare hash, which a recording let a
//! guesser test (issue 30, finding 1). The pilot sets the phrase again and binds.

use telemetry::link::LinkKey;
use telemetry::settings::module as schema;

use super::table::{ROWS, Row};
use super::{RateMode, Settings};
use crate::hm10::at::Pin;

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
pub const RECORD_VERSION: u8 = 8;
/// Record length of the current version.
pub const RECORD_LEN: usize = 100;
/// Record length of version 7 (no dynamic power).
pub const RECORD_V7_LEN: usize = 99;
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
/// Where version 4's bound models (u64 LE) start.
const MODELS_AT: usize = RECORD_V3_LEN + 1;
/// Where version 7's unauthenticated setting sits (after the phrase's derivation).
const PLAIN_AT: usize = RECORD_V7_LEN - 1;

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
    /// The current (version 8) record: the table's fields ([`ROWS`]), then the bound
    /// models, the key, the PIN and the phrase's derivation.
    pub fn to_record(&self) -> [u8; RECORD_LEN] {
        let mut record = [0u8; RECORD_LEN];
        if let Some(version) = record.first_mut() {
            *version = RECORD_VERSION;
        }
        for row in &ROWS {
            if let Some(field) = record.get_mut(row.stored.range()) {
                row.stored.encode((row.get)(self), field);
            }
        }
        let (flag, key) = match self.link_key {
            Some(key) => (1, key.to_bytes()),
            None => (0, [0; 16]),
        };
        let pin = self.ble_pin.map_or(FACTORY_PIN, Pin::value);
        let (phrase_flag, prs) = match self.phrase_prs {
            Some(prs) => (1, prs),
            None => (0, [0; 32]),
        };
        let tails: [(usize, &[u8]); 7] = [
            (MODELS_AT, &self.bound_models.to_le_bytes()),
            (RECORD_V5_LEN, &[flag]),
            (RECORD_V5_LEN + 1, &key),
            (RECORD_V5_LEN + 17, &pin.to_le_bytes()),
            (RECORD_V6_LEN, &[phrase_flag]),
            (RECORD_V6_LEN + 1, &self.phrase_salt),
            (RECORD_V6_LEN + 9, &prs),
        ];
        for (offset, bytes) in tails {
            if let Some(field) = record.get_mut(offset..offset + bytes.len()) {
                field.copy_from_slice(bytes);
            }
        }
        record
    }

    /// Parses a record of version 1 … 8; every field is range-checked, a field an older
    /// version lacks takes its factory value.
    pub fn from_record(record: &[u8]) -> Result<Self, DecodeError> {
        let version = version_of(record)?;
        let field = |offset: usize| DecodeError::Field { offset };
        let mut settings = Settings::default();
        for row in &ROWS {
            let Some(bytes) = record.get(row.stored.range()) else {
                continue;
            };
            let offset = row.stored.offset();
            let value = row.stored.decode(bytes).ok_or(field(offset))?;
            let value = older_meaning(version, row, value).ok_or(field(offset))?;
            if !row.assign(&mut settings, value) {
                return Err(field(offset));
            }
        }
        if let Some(models) = record.get(MODELS_AT..RECORD_V4_LEN) {
            let models: [u8; 8] = models.try_into().map_err(|_| field(MODELS_AT))?;
            settings.bound_models = u64::from_le_bytes(models);
        }
        let security = record.get(RECORD_V5_LEN..RECORD_V6_LEN).unwrap_or(&[]);
        if let [flag, tail @ ..] = security {
            (settings.link_key, settings.ble_pin) = decode_security(*flag, tail)?;
        }
        if let Some(phrase) = record.get(RECORD_V6_LEN..PLAIN_AT) {
            (settings.phrase_salt, settings.phrase_prs) = decode_phrase(phrase)?;
        }
        if version < 7 {
            // Bound before the key agreement: no link (module doc).
            settings.bind_id = 0;
            settings.bound_models = 0;
            settings.link_key = None;
        }
        Ok(settings)
    }
}

/// The record's version, once its length is checked against it.
fn version_of(record: &[u8]) -> Result<u8, DecodeError> {
    let Some(&version) = record.first() else {
        return Err(DecodeError::Length { found: 0 });
    };
    let expected = match version {
        1 => RECORD_V1_LEN,
        2 => RECORD_V2_LEN,
        3 => RECORD_V3_LEN,
        4 => RECORD_V4_LEN,
        5 => RECORD_V5_LEN,
        6 => RECORD_V6_LEN,
        7 => RECORD_V7_LEN,
        RECORD_VERSION => RECORD_LEN,
        found => return Err(DecodeError::Version { found }),
    };
    if record.len() == expected {
        Ok(version)
    } else {
        Err(DecodeError::Length {
            found: record.len(),
        })
    }
}

const RATE_KEY: u16 = schema::RATE.key;
const INPUT_KEY: u16 = schema::INPUT.key;
const BAND_KEY: u16 = schema::BAND.key;

/// A stored value in today's terms: versions 1 and 2 stored the rate as a bit-rate code and
/// knew neither the fastest CRSF input nor the ISM plan (index 3 of both); `None`: a value
/// no writer of `version` produced.
fn older_meaning(version: u8, row: &Row, value: u32) -> Option<u32> {
    if version >= 3 {
        return Some(value);
    }
    match row.key {
        RATE_KEY => u8::try_from(value)
            .ok()
            .and_then(rate_from_old_code)
            .map(|rate| u32::from(rate.code())),
        INPUT_KEY | BAND_KEY if value == 3 => None,
        _ => Some(value),
    }
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

/// Version 7's phrase fields (the flag, the salt, the derivation: all 0 without a phrase).
fn decode_phrase(tail: &[u8]) -> Result<([u8; 8], Option<[u8; 32]>), DecodeError> {
    let field = |offset: usize| DecodeError::Field { offset };
    let Some((flag, rest)) = tail.split_first() else {
        return Ok(([0; 8], None));
    };
    let (salt, rest) = rest
        .split_first_chunk::<8>()
        .ok_or(field(RECORD_V6_LEN + 1))?;
    let prs: &[u8; 32] = rest.try_into().map_err(|_| field(RECORD_V6_LEN + 9))?;
    let prs = match flag {
        0 if prs.iter().all(|b| *b == 0) => None,
        0 => return Err(field(RECORD_V6_LEN + 9)),
        1 => Some(*prs),
        _ => return Err(field(RECORD_V6_LEN)),
    };
    Ok((*salt, prs))
}

#[cfg(test)]
#[path = "record_tests.rs"]
mod tests;
