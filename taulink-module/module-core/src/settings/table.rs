//! The module's settings as one table: each row binds one setting of the protocol crate's
//! schema (`telemetry::settings::module`: key, name, range or choice words, factory value)
//! to its field in [`Settings`], its place in the on-flash record, its CRSF parameter (number,
//! folder, label and options, as the radio's device tool shows it) and what a change from the
//! radio does. The record decoder and encoder, the text path (`settings::text`), the CRSF
//! parameters (`crate::params`) and [`Settings::default`] are loops over [`ROWS`]; adding a
//! setting is one row here (and its schema row).
//!
//! A row's value is the schema's: a choice's index, or the number itself.

use telemetry::link::{Band, RateMode};
use telemetry::settings::module as schema;
use telemetry::settings::module::MODULE_PARAMS;
use telemetry::settings::{Kind, Param, Value};

use super::openlrs::{LinkProtocol, carrier_in_range};
use super::{InputProtocol, OutputProtocol, Role, Settings, TELEMETRY_RATIOS};
use crate::params::{
    BAND, DYNAMIC_POWER, HANDSET_FOLDER as HANDSET, INPUT, INPUT_TIMEOUT, MODEL_MATCH,
    OPENLRS_CHANNELS, OPENLRS_FOLDER as OPENLRS, OPENLRS_RATE, OPENLRS_TELEMETRY, PACKET_RATE,
    PPM_FAILSAFE, PROTOCOL, RECEIVER_FOLDER as RECEIVER, TELEMETRY_OUTPUT, TELEMETRY_RATIO,
    TX_POWER,
};
use crate::ppm::FailsafeOutput;

/// Where a row's value sits in the current record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stored {
    /// `width` bytes at `offset`, little-endian: the value as it is.
    Le {
        /// Byte offset in the record.
        offset: usize,
        /// Bytes, 1…4.
        width: usize,
    },
    /// One byte at `offset`: the choice's index plus one (OpenLRSng's channel modes count
    /// from 1).
    FromOne {
        /// Byte offset in the record.
        offset: usize,
    },
}

impl Stored {
    /// The byte offset of the field.
    pub const fn offset(self) -> usize {
        match self {
            Self::Le { offset, .. } | Self::FromOne { offset } => offset,
        }
    }

    /// The field's bytes in the record.
    pub const fn range(self) -> core::ops::Range<usize> {
        match self {
            Self::Le { offset, width } => offset..offset + width,
            Self::FromOne { offset } => offset..offset + 1,
        }
    }

    /// The row's value from the field's bytes (`None`: a byte no writer produces).
    pub fn decode(self, bytes: &[u8]) -> Option<u32> {
        let value = bytes
            .iter()
            .rev()
            .fold(0u32, |v, b| (v << 8) | u32::from(*b));
        match self {
            Self::Le { .. } => Some(value),
            Self::FromOne { .. } => value.checked_sub(1),
        }
    }

    /// The field's bytes for `value`, into `field` (the record's slice for [`Self::range`]).
    pub fn encode(self, value: u32, field: &mut [u8]) {
        let value = match self {
            Self::Le { .. } => value,
            Self::FromOne { .. } => value.wrapping_add(1),
        };
        for (byte, b) in field.iter_mut().zip(value.to_le_bytes()) {
            *byte = b;
        }
    }
}

/// How the radio's device tool shows a row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Options {
    /// A selection, one label per choice (or per number in `values`).
    Labels(&'static [&'static str]),
    /// A selection over these numbers of a number row, one label each.
    Values(&'static [&'static str], &'static [u8]),
    /// A 16-bit number in the row's range, with its unit.
    Uint16(&'static str),
}

/// A row's CRSF parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crsf {
    /// The parameter's number (`crate::params`).
    pub number: u8,
    /// Its folder's number (0: the top level).
    pub folder: u8,
    /// The name the radio shows.
    pub label: &'static str,
    /// Its options.
    pub options: Options,
}

/// What a change of the row asks of the running module.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnChange {
    /// The link restarts with the new value.
    RestartLink,
    /// An OpenLRSng parameter: the link restarts if it is OpenLRSng.
    OpenLrs,
    /// Read at power-up only (the radio's row says so).
    PowerUp,
    /// The link's input timeout changes.
    InputTimeout,
    /// The PPM encoder's failsafe changes.
    PpmFailsafe,
    /// The link's power limits change (maximum, dynamic): from the next slot on.
    TxPower,
}

/// One setting.
#[derive(Debug, Clone, Copy)]
pub struct Row {
    /// Its schema row's key ([`Row::param`]: name, range or choices, factory value).
    pub key: u16,
    /// The schema's smallest value (0 for a choice).
    pub min: u32,
    /// The schema's largest value (a choice's last index).
    pub max: u32,
    /// The schema's factory value.
    pub default: u32,
    /// Its field in the record.
    pub stored: Stored,
    /// Its CRSF parameter, if the radio shows it.
    pub crsf: Option<Crsf>,
    /// What a change does.
    pub on_change: OnChange,
    /// The field's value.
    pub get: fn(&Settings) -> u32,
    /// Sets the field to a value within the schema's range if the field can take it;
    /// `false` (nothing set) for any other ([`Row::assign`] checks the range first).
    pub set: fn(&mut Settings, u32) -> bool,
}

impl Row {
    /// Its schema row: name and choice words (the text path, tools). The firmware reads
    /// only the range and factory value the row took from it when compiled, so it links no
    /// name or word.
    pub fn param(&self) -> Option<&'static Param> {
        MODULE_PARAMS.iter().copied().find(|p| p.key == self.key)
    }

    /// Whether `value` lies within the schema's range or choices.
    pub fn in_range(&self, value: u32) -> bool {
        (self.min..=self.max).contains(&value)
    }

    /// Sets the field to `value` if the row holds it: within the schema's range or choices,
    /// and one the field can take (a telemetry ratio the link runs, a carrier inside a
    /// module range). `false`: nothing changed.
    pub fn assign(&self, settings: &mut Settings, value: u32) -> bool {
        self.in_range(value) && (self.set)(settings, value)
    }
}

/// A row for schema row `param`: its key, range and factory value taken when compiling.
const fn row(
    param: &Param,
    stored: Stored,
    crsf: Option<Crsf>,
    on_change: OnChange,
    get: fn(&Settings) -> u32,
    set: fn(&mut Settings, u32) -> bool,
) -> Row {
    let (min, max) = match param.kind {
        Kind::U32 { min, max } => (min, max),
        Kind::Choice(words) => (0, words.len().saturating_sub(1) as u32),
        // No real-valued module setting: an empty range.
        Kind::F32 { .. } => (1, 0),
    };
    let default = match param.default {
        Value::U32(v) => v,
        Value::F32(_) => 0,
    };
    Row {
        key: param.key,
        min,
        max,
        default,
        stored,
        crsf,
        on_change,
        get,
        set,
    }
}

/// The row named `name`, with its schema row.
pub fn by_name(name: &str) -> Option<(&'static Row, &'static Param)> {
    let param = MODULE_PARAMS.iter().copied().find(|p| p.name == name)?;
    ROWS.iter().find(|r| r.key == param.key).map(|r| (r, param))
}

/// The row behind CRSF parameter `number`.
pub fn by_crsf(number: u8) -> Option<(&'static Row, Crsf)> {
    ROWS.iter()
        .find_map(|r| r.crsf.filter(|c| c.number == number).map(|c| (r, c)))
}

/// The value `index` of a list of alternatives stands for (`None` past the end).
fn pick<T: Copy>(list: &[T], index: u32) -> Option<T> {
    list.get(index as usize).copied()
}

/// Sets a field through `pick`.
fn put<T>(field: &mut T, value: Option<T>) -> bool {
    match value {
        Some(v) => {
            *field = v;
            true
        }
        None => false,
    }
}

const ROLES: [Role; 2] = [Role::Transmitter, Role::Receiver];
const INPUTS: [InputProtocol; 4] = [
    InputProtocol::Ppm,
    InputProtocol::Crsf,
    InputProtocol::Crsf115200,
    InputProtocol::Crsf921600,
];
const OUTPUTS: [OutputProtocol; 4] = [
    OutputProtocol::Off,
    OutputProtocol::Crsf,
    OutputProtocol::SPort,
    OutputProtocol::FrskyHub,
];
const FAILSAFES: [FailsafeOutput; 2] = [FailsafeOutput::HoldLast, FailsafeOutput::StopPulses];

const fn crsf(number: u8, folder: u8, label: &'static str, options: Options) -> Option<Crsf> {
    Some(Crsf {
        number,
        folder,
        label,
        options,
    })
}

const fn byte(offset: usize) -> Stored {
    Stored::Le { offset, width: 1 }
}

const fn word(offset: usize) -> Stored {
    Stored::Le { offset, width: 4 }
}

/// The names the radio shows for the rate modes, with their packet rates (code order).
const RATE_LABELS: [&str; 5] = [
    "L50 (50 Hz)",
    "M100 (100 Hz)",
    "F250 (250 Hz)",
    "F500 (500 Hz)",
    "F700 (700 Hz)",
];
/// The telemetry ratios as the radio shows them ([`TELEMETRY_RATIOS`] order).
const RATIO_LABELS: [&str; 7] = ["1:2", "1:4", "1:8", "1:16", "1:32", "1:64", "1:128"];
/// The RFM22B's eight power steps (`radio_rfm22b::TxPower`): nominal dBm and mW.
const TX_POWER_LABELS: [&str; 8] = [
    "1dBm 1mW",
    "2dBm 2mW",
    "5dBm 3mW",
    "8dBm 6mW",
    "11dBm 13mW",
    "14dBm 25mW",
    "17dBm 50mW",
    "20dBm 100mW",
];
/// Band options, in `Band` order, with their legal meaning.
const BAND_LABELS: [&str; 4] = ["433 HAM licence", "868 EU SRD", "915 US ISM", "433 ISM LPD"];
const INPUT_LABELS: [&str; 4] = ["PPM", "CRSF 400k", "CRSF 115k", "CRSF 921k"];
const OUTPUT_LABELS: [&str; 4] = ["Off", "CRSF", "S.Port", "FrSky D"];
const FAILSAFE_LABELS: [&str; 2] = ["Hold last", "Stop pulses"];
const OFF_ON_LABELS: [&str; 2] = ["Off", "On"];
/// Protocol options, in `LinkProtocol` order: the OpenLRSng ones say they are unauthenticated.
const PROTOCOL_LABELS: [&str; 3] = ["TauLink", "OLRSng3.8 (no auth)", "OLRSng3.9 (no auth)"];
/// OpenLRSng's modem profiles.
const OPENLRS_RATE_LABELS: [&str; 5] = ["4800bps", "9600bps", "19k2bps", "57k6bps", "125kbps"];
/// OpenLRSng's channel modes 1..6.
const OPENLRS_CHANNEL_LABELS: [&str; 6] = ["4+4", "8", "8+4", "12", "12+4", "16"];

/// Every setting, in the record's order (the `telemetry::settings::module` rows').
pub static ROWS: [Row; 19] = [
    row(
        &schema::ROLE,
        byte(1),
        None,
        OnChange::RestartLink,
        |s| s.role as u32,
        |s, v| put(&mut s.role, pick(&ROLES, v)),
    ),
    row(
        &schema::RATE,
        byte(2),
        crsf(PACKET_RATE, 0, "Packet Rate", Options::Labels(&RATE_LABELS)),
        OnChange::RestartLink,
        |s| u32::from(s.rate.code()),
        |s, v| put(&mut s.rate, pick(&RateMode::ALL, v)),
    ),
    row(
        &schema::INPUT,
        byte(3),
        crsf(INPUT, HANDSET, "Input", Options::Labels(&INPUT_LABELS)),
        OnChange::PowerUp,
        |s| s.input as u32,
        |s, v| put(&mut s.input, pick(&INPUTS, v)),
    ),
    row(
        &schema::OUTPUT,
        byte(4),
        crsf(
            TELEMETRY_OUTPUT,
            HANDSET,
            "Telem Output",
            Options::Labels(&OUTPUT_LABELS),
        ),
        OnChange::PowerUp,
        |s| s.output as u32,
        |s, v| put(&mut s.output, pick(&OUTPUTS, v)),
    ),
    row(
        &schema::BAND,
        byte(5),
        crsf(BAND, 0, "Band", Options::Labels(&BAND_LABELS)),
        OnChange::RestartLink,
        |s| u32::from(s.band.code()),
        |s, v| put(&mut s.band, u8::try_from(v).ok().and_then(Band::from_code)),
    ),
    row(
        &schema::TX_POWER,
        byte(6),
        crsf(TX_POWER, 0, "TX Power", Options::Labels(&TX_POWER_LABELS)),
        OnChange::TxPower,
        |s| u32::from(s.tx_power),
        |s, v| put(&mut s.tx_power, u8::try_from(v).ok().filter(|p| *p <= 7)),
    ),
    row(
        &schema::FAILSAFE,
        byte(7),
        crsf(
            PPM_FAILSAFE,
            RECEIVER,
            "PPM Failsafe",
            Options::Labels(&FAILSAFE_LABELS),
        ),
        OnChange::PpmFailsafe,
        |s| s.failsafe as u32,
        |s, v| put(&mut s.failsafe, pick(&FAILSAFES, v)),
    ),
    row(
        &schema::BIND_ID,
        word(8),
        None,
        OnChange::RestartLink,
        |s| s.bind_id,
        |s, v| put(&mut s.bind_id, Some(v)),
    ),
    row(
        &schema::INPUT_TIMEOUT_MS,
        Stored::Le {
            offset: 12,
            width: 2,
        },
        crsf(
            INPUT_TIMEOUT,
            HANDSET,
            "Input Timeout",
            Options::Uint16("ms"),
        ),
        OnChange::InputTimeout,
        |s| u32::from(s.input_timeout_ms),
        |s, v| put(&mut s.input_timeout_ms, u16::try_from(v).ok()),
    ),
    row(
        &schema::TELEMETRY_RATIO,
        byte(14),
        crsf(
            TELEMETRY_RATIO,
            0,
            "Telem Ratio",
            Options::Values(&RATIO_LABELS, &TELEMETRY_RATIOS),
        ),
        OnChange::RestartLink,
        |s| u32::from(s.telemetry_ratio),
        |s, v| {
            let ratio = u8::try_from(v).ok();
            put(
                &mut s.telemetry_ratio,
                ratio.filter(|r| TELEMETRY_RATIOS.contains(r)),
            )
        },
    ),
    row(
        &schema::MODEL_MATCH,
        byte(15),
        crsf(
            MODEL_MATCH,
            0,
            "Model Match",
            Options::Labels(&OFF_ON_LABELS),
        ),
        OnChange::RestartLink,
        |s| u32::from(s.model_match),
        |s, v| put(&mut s.model_match, pick(&[false, true], v)),
    ),
    row(
        &schema::PROTOCOL,
        byte(24),
        crsf(PROTOCOL, 0, "Protocol", Options::Labels(&PROTOCOL_LABELS)),
        OnChange::RestartLink,
        |s| u32::from(s.protocol.code()),
        |s, v| {
            let protocol = u8::try_from(v).ok().and_then(LinkProtocol::from_code);
            put(&mut s.protocol, protocol)
        },
    ),
    row(
        &schema::OLRS_PROFILE,
        byte(25),
        crsf(
            OPENLRS_RATE,
            OPENLRS,
            "OLRS Rate",
            Options::Labels(&OPENLRS_RATE_LABELS),
        ),
        OnChange::OpenLrs,
        |s| u32::from(s.openlrs.profile),
        |s, v| put(&mut s.openlrs.profile, u8::try_from(v).ok()),
    ),
    row(
        &schema::OLRS_CHANNELS_MODE,
        Stored::FromOne { offset: 26 },
        crsf(
            OPENLRS_CHANNELS,
            OPENLRS,
            "OLRS Channels",
            Options::Labels(&OPENLRS_CHANNEL_LABELS),
        ),
        OnChange::OpenLrs,
        |s| u32::from(s.openlrs.channel_mode.saturating_sub(1)),
        |s, v| {
            let mode = u8::try_from(v).ok().and_then(|i| i.checked_add(1));
            put(&mut s.openlrs.channel_mode, mode)
        },
    ),
    row(
        &schema::OLRS_TELEMETRY,
        byte(27),
        crsf(
            OPENLRS_TELEMETRY,
            OPENLRS,
            "OLRS Telem",
            Options::Labels(&OFF_ON_LABELS),
        ),
        OnChange::OpenLrs,
        |s| u32::from(s.openlrs.telemetry),
        |s, v| put(&mut s.openlrs.telemetry, pick(&[false, true], v)),
    ),
    row(
        &schema::OLRS_FREQUENCY_HZ,
        word(28),
        None,
        OnChange::OpenLrs,
        |s| s.openlrs.frequency_hz,
        |s, v| {
            put(
                &mut s.openlrs.frequency_hz,
                Some(v).filter(|f| carrier_in_range(*f)),
            )
        },
    ),
    row(
        &schema::OLRS_HOP_SEED,
        word(32),
        None,
        OnChange::OpenLrs,
        |s| s.openlrs.hop_seed,
        |s, v| put(&mut s.openlrs.hop_seed, Some(v)),
    ),
    row(
        &schema::PLAIN,
        byte(98),
        None,
        OnChange::RestartLink,
        |s| u32::from(s.plain),
        |s, v| put(&mut s.plain, pick(&[false, true], v)),
    ),
    row(
        &schema::DYNAMIC_POWER,
        byte(99),
        crsf(
            DYNAMIC_POWER,
            0,
            "Dynamic Power",
            Options::Labels(&OFF_ON_LABELS),
        ),
        OnChange::TxPower,
        |s| u32::from(s.dynamic_power),
        |s, v| put(&mut s.dynamic_power, pick(&[false, true], v)),
    ),
];

#[cfg(test)]
#[path = "table_tests.rs"]
mod tests;
