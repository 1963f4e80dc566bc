//! The module's settings and their on-flash record. Every setting with a value of its own
//! is one row of [`table`] (its schema row in `telemetry::settings::module`, its field, its
//! place in the record, its CRSF parameter, the effect of a change); the record, the text
//! path and the CRSF parameters loop over it.
//!
//! The record is one versioned, fixed-size byte string stored under one key, so a save is
//! a single sequential-storage item write: after a power cut the map holds either the old
//! or the new record (the item CRC rejects a torn write), never a mix of fields.
//! The record itself (layout, versions 1 … 6) is [`record`]'s.

pub mod openlrs;
pub mod record;
pub mod store;
pub mod table;
pub mod text;

pub use openlrs::{LinkProtocol, OpenLrsError, OpenLrsSettings};
pub use record::{
    DecodeError, RECORD_LEN, RECORD_V1_LEN, RECORD_V2_LEN, RECORD_V3_LEN, RECORD_V4_LEN,
    RECORD_V5_LEN, RECORD_VERSION, rate_from_old_code,
};
pub use store::{SettingsStore, StoreError};
pub use text::TextError;

use telemetry::link::phrase::{PRS_BYTES, SALT_BYTES};
use telemetry::link::{LinkKey, PhraseSecret};
use telemetry::settings::module as schema;
use telemetry::settings::{Kind, Param, Value};

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
    /// The link key (spec §12.1): in the transmitter role the module's own random key, each
    /// link's key derived from it and handed over at bind ([`LinkKey::for_link`]); in the
    /// receiver role the key the master handed over. `None`: not bound with a key agreement
    /// (the link runs only unauthenticated, when [`Settings::plain`] allows it).
    pub link_key: Option<LinkKey>,
    /// The salt of the binding phrase's derivation (drawn once per module, public: it
    /// travels in bind offers and phone challenges).
    pub phrase_salt: [u8; SALT_BYTES],
    /// The binding phrase's slow derivation under `phrase_salt`
    /// ([`telemetry::link::PhraseSecret`]): what CPace runs on at bind and with the phone.
    /// `None`: no phrase (binds agree a key without one). The phrase itself is never stored.
    pub phrase_prs: Option<[u8; PRS_BYTES]>,
    /// The explicit setting for an unauthenticated link (spec §12.1): binds agree no key and
    /// a link without one runs. Off: every bind agrees a key.
    pub plain: bool,
    /// Dynamic transmit power (`telemetry::link::power`): the power follows how the other
    /// end hears us, up to [`Settings::tx_power`]; off, always `tx_power`.
    pub dynamic_power: bool,
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
/// Factory telemetry ratio (the schema's): one slot in 4.
pub const DEFAULT_TELEMETRY_RATIO: u8 = whole(&schema::TELEMETRY_RATIO).1 as u8;

/// Range of [`Settings::input_timeout_ms`] (the schema's, `telemetry::settings::module`).
pub const INPUT_TIMEOUT_MS: core::ops::RangeInclusive<u16> = {
    let (range, _) = whole(&schema::INPUT_TIMEOUT_MS);
    (*range.start() as u16)..=(*range.end() as u16)
};
/// Factory input timeout (the schema's): the flight side is in failsafe within 1 s of the
/// input stopping.
pub const DEFAULT_INPUT_TIMEOUT_MS: u16 = whole(&schema::INPUT_TIMEOUT_MS).1 as u16;

/// A whole-number schema row's range and factory value (constants of the field types
/// derive from it; the schema's values all fit them, `table`'s tests check).
const fn whole(param: &Param) -> (core::ops::RangeInclusive<u32>, u32) {
    let range = match param.kind {
        Kind::U32 { min, max } => min..=max,
        Kind::F32 { .. } | Kind::Choice(_) => 0..=0,
    };
    let default = match param.default {
        Value::U32(v) => v,
        Value::F32(_) => 0,
    };
    (range, default)
}

impl Settings {
    /// The fields before the table's factory values are set ([`Settings::default`]); the
    /// rest are the factory state: not bound, no key, no phrase, the factory PIN.
    const BLANK: Self = Self {
        role: Role::Transmitter,
        rate: RateMode::L50,
        input: InputProtocol::Ppm,
        output: OutputProtocol::Off,
        band: Band::Mhz433,
        tx_power: 0,
        failsafe: FailsafeOutput::HoldLast,
        bind_id: 0,
        input_timeout_ms: 0,
        telemetry_ratio: 0,
        model_match: false,
        bound_models: 0,
        protocol: LinkProtocol::TauLink,
        openlrs: OpenLrsSettings {
            frequency_hz: 0,
            profile: 0,
            channel_mode: 0,
            telemetry: false,
            hop_seed: 0,
        },
        link_key: None,
        phrase_salt: [0; SALT_BYTES],
        phrase_prs: None,
        plain: false,
        dynamic_power: false,
        ble_pin: None,
    };
}

impl Default for Settings {
    /// Every table row at the schema's factory value (each one a value its row holds,
    /// `table`'s tests check), not bound, no key, phrase or PIN of its own.
    fn default() -> Self {
        let mut settings = Self::BLANK;
        for row in &table::ROWS {
            (row.set)(&mut settings, row.default);
        }
        settings
    }
}

impl Settings {
    /// The binding phrase's derivation, if a phrase is set.
    pub fn phrase(&self) -> Option<PhraseSecret> {
        self.phrase_prs.map(|prs| PhraseSecret {
            salt: self.phrase_salt,
            prs,
        })
    }

    /// Whether the whole set runs (`openlrs::check`: an OpenLRSng link's carrier and hops
    /// inside the band plan, transmitter role). Every settings path checks it before a
    /// change sticks.
    pub fn validate(&self) -> Result<(), OpenLrsError> {
        openlrs::check(self)
    }
}
