//! The flight controller's settings as they travel over the link: the schema both ends and
//! every tool read — each setting's stable key, dotted name, type, range, unit, factory value
//! and meaning, in one table ([`PARAMS`]). A `SettingChange`'s `id` is the row's index in
//! that table and its `value` the row's 32 stored bits (reals as IEEE-754, whole numbers and
//! choices as themselves); the flight side applies and stores it, the console, the web
//! ground station and the module's tools name and check it with the same rows. The choice
//! words a person types (`link.protocol openlrs38`, `link.rate F500`) are spelt once here and
//! read case-insensitively on every end.
//!
//! The module's settings are described with the same rows in [`module`].
//!
//! What the flight side does with a set (whether the whole set runs, its storage in flash,
//! the binding phrase's key, which lives outside the table) is `flight_core::settings`.

mod handle;
pub mod module;
mod table;

pub use handle::{Bits, Change, Handle, ParamType};
pub use table::{
    ARM_ON_CRITICAL, BANDS, CHANNEL_FORMATS, COUNT, FRAMES, INS_MODES, LOG_PROFILES, LOOP_RATES,
    MODES, OUTPUT_PROTOCOLS, PARAMS, PROTOCOLS, RATES, handles,
};

/// A setting's value.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Value {
    /// A real number.
    F32(f32),
    /// A whole number, or the index of a choice.
    U32(u32),
}

impl Value {
    /// The 32 bits stored in flash and sent in a `SettingChange`.
    pub fn to_bits(self) -> u32 {
        match self {
            Value::F32(v) => v.to_bits(),
            Value::U32(v) => v,
        }
    }
}

/// The names of an enumerated setting, in the order of their stored index.
pub type Choice = &'static [&'static str];

/// What a setting holds, with its limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A real number in `min..=max`.
    F32 {
        /// Smallest allowed.
        min: f32,
        /// Largest allowed.
        max: f32,
    },
    /// A whole number in `min..=max`.
    U32 {
        /// Smallest allowed.
        min: u32,
        /// Largest allowed.
        max: u32,
    },
    /// One of named options (stored as its index).
    Choice(Choice),
}

/// One row of the table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Param {
    /// Stable flash key; never reuse one.
    pub key: u16,
    /// Dotted name (console, ground station, tools); its last word names the unit
    /// ([`Param::unit`]).
    pub name: &'static str,
    /// Type and range.
    pub kind: Kind,
    /// Factory value.
    pub default: Value,
}

/// Why a value does not fit a setting's row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ValueError {
    /// No setting by that name, key or index.
    Unknown,
    /// Outside the row's range, not one of its choices, or of the other type.
    OutOfRange,
    /// Not a number, or not one of the row's choice words.
    Unparsable,
}

impl core::fmt::Display for ValueError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ValueError::Unknown => "no such setting",
            ValueError::OutOfRange => "value out of range",
            ValueError::Unparsable => "cannot read that value",
        })
    }
}

impl core::error::Error for ValueError {}

/// The unit each name ending stands for: the table names a physical quantity with its unit
/// last (`rate.max_dps`, `output.min_us`); longer endings first.
const UNITS: [(&str, &str); 10] = [
    ("_mv_per_a", "mV/A"),
    ("_frequency_hz", "Hz"),
    ("_hz", "Hz"),
    ("_us", "µs"),
    ("_ms", "ms"),
    ("_mv", "mV"),
    ("_dps", "°/s"),
    ("_deg", "°"),
    ("_mps", "m/s"),
    ("_s", "s"),
];

impl Param {
    /// The unit its value is in ("°/s", "µs"), from its name's last word; "" for a pure
    /// number or a choice.
    pub fn unit(&self) -> &'static str {
        if matches!(self.kind, Kind::Choice(_)) {
            return "";
        }
        UNITS
            .iter()
            .find(|(ending, _)| self.name.ends_with(ending))
            .map_or("", |(_, unit)| unit)
    }

    /// What the setting does, for help texts and the ground station (one line).
    pub fn doc(&self) -> &'static str {
        find(self.name)
            .and_then(|(i, _)| table::DOCS.get(i))
            .copied()
            .unwrap_or("")
    }

    /// Checks `value` against the kind and range.
    pub fn check(&self, value: Value) -> Result<Value, ValueError> {
        match (self.kind, value) {
            (Kind::F32 { min, max }, Value::F32(v))
                if v.is_finite() && (min..=max).contains(&v) =>
            {
                Ok(value)
            }
            (Kind::U32 { min, max }, Value::U32(v)) if (min..=max).contains(&v) => Ok(value),
            (Kind::Choice(names), Value::U32(v)) if (v as usize) < names.len() => Ok(value),
            _ => Err(ValueError::OutOfRange),
        }
    }

    /// Rebuilds a value from its stored (or sent) bits, checked.
    pub fn from_bits(&self, bits: u32) -> Result<Value, ValueError> {
        self.check(self.value_of(bits))
    }

    /// The value its stored bits stand for, unchecked (the kind decides the type).
    pub fn value_of(&self, bits: u32) -> Value {
        match self.kind {
            Kind::F32 { .. } => Value::F32(f32::from_bits(bits)),
            Kind::U32 { .. } | Kind::Choice(_) => Value::U32(bits),
        }
    }

    /// A choice row's value for one of its words (any letter case); numbers are read by the
    /// end that parses them.
    pub fn choice(&self, word: &str) -> Result<Value, ValueError> {
        match self.kind {
            Kind::Choice(names) => choice_index(names, word)
                .map(|i| Value::U32(i as u32))
                .ok_or(ValueError::Unparsable),
            Kind::F32 { .. } | Kind::U32 { .. } => Err(ValueError::Unparsable),
        }
    }
}

/// Where `word` is among `names`, any letter case (the one spelling of each value, as both
/// link ends read it).
pub fn choice_index(names: &[&str], word: &str) -> Option<usize> {
    names.iter().position(|n| n.eq_ignore_ascii_case(word))
}

/// Looks a setting up by name: its index (the `SettingChange` id) and row.
pub fn find(name: &str) -> Option<(usize, &'static Param)> {
    PARAMS.iter().enumerate().find(|(_, p)| p.name == name)
}

/// The row with `id` (a `SettingChange`'s id).
pub fn by_id(id: u16) -> Option<&'static Param> {
    PARAMS.get(usize::from(id))
}

#[cfg(test)]
mod tests;
