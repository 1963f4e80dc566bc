//! The flight side's set of values over the schema's table ([`telemetry::settings`]: each
//! setting's key, name, kind, range and factory value). Values outside a row's range are
//! refused, never clamped silently, and so is any change after which the whole set would not
//! run ([`crate::pipeline::validate`]): a change leaves the set valid or untouched. Numbers
//! typed at the console are read here ([`ParamText`]: the exact decimal reader the firmware
//! is built with); choice words by the schema, one spelling on every end.

use telemetry::link::LinkKey;
pub use telemetry::settings::COUNT;
use telemetry::settings::find;
use telemetry::settings::{
    Bits, Change, Handle, Kind, PARAMS, Param, ParamType, Value, ValueError,
};

use super::decimal;
use crate::pipeline::{InvalidSettings, validate};

/// Why a value was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParamError {
    /// No parameter by that name or key.
    Unknown,
    /// Outside the parameter's range, or not one of its choices.
    OutOfRange,
    /// Not a number / not a choice name (or, for several pairs, a name without a value).
    Unparsable,
    /// The value is fine on its own, but the whole set would not run (nothing changed).
    Invalid(InvalidSettings),
}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ParamError::Unknown => "no such setting",
            ParamError::OutOfRange => "value out of range",
            ParamError::Unparsable => "cannot read that value",
            ParamError::Invalid(e) => return write!(f, "refused, the settings would not run: {e}"),
        })
    }
}

impl core::error::Error for ParamError {}

impl From<ValueError> for ParamError {
    fn from(e: ValueError) -> Self {
        match e {
            ValueError::Unknown => ParamError::Unknown,
            ValueError::OutOfRange => ParamError::OutOfRange,
            ValueError::Unparsable => ParamError::Unparsable,
        }
    }
}

/// Most name/value pairs one `set` line may change together.
pub const MAX_PAIRS: usize = 8;

/// A row's value from console text.
pub trait ParamText {
    /// Reads a value from console text: a number, or one of a choice's words (any case).
    fn parse(&self, text: &str) -> Result<Value, ParamError>;
}

impl ParamText for Param {
    // Console text only, never the loop: `#[inline]` (with `Settings::set_text` and
    // `set_text_pairs`, its only callers) so it is compiled where the console is, in
    // `flight-app` (built for size), rather than in this crate, built for speed.
    #[inline]
    fn parse(&self, text: &str) -> Result<Value, ParamError> {
        let value = match self.kind {
            Kind::F32 { .. } => Value::F32(decimal::parse(text).ok_or(ParamError::Unparsable)?),
            Kind::U32 { .. } => Value::U32(text.parse().map_err(|_| ParamError::Unparsable)?),
            Kind::Choice(_) => self.choice(text)?,
        };
        Ok(self.check(value)?)
    }
}

/// The current value of every parameter, and the link key.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Each parameter's stored bits in table order; its row's kind says how to read them
    /// (a [`Handle`] reads them as its type).
    values: Bits,
    /// The link key derived from the binding phrase (spec §12), outside the table: it is
    /// no parameter a `list`, `get` or `SettingChange` can read, only the console's `phrase`
    /// sets it. `None`: no phrase, the link runs unauthenticated.
    link_key: Option<LinkKey>,
}

impl Default for Settings {
    fn default() -> Self {
        let mut values = [0; COUNT];
        for (v, p) in values.iter_mut().zip(PARAMS) {
            *v = p.default.to_bits();
        }
        Self {
            values,
            link_key: None,
        }
    }
}

impl Settings {
    /// The link key (from the binding phrase), if one is set.
    pub fn link_key(&self) -> Option<LinkKey> {
        self.link_key
    }

    /// Sets or clears the link key (the console's `phrase`; the key only, never the
    /// phrase, is kept).
    pub fn set_link_key(&mut self, key: Option<LinkKey>) {
        self.link_key = key;
    }

    /// A parameter's value, typed by its handle (`settings.get(handles::RATE_MAX_DPS)`).
    pub fn get<T: ParamType>(&self, handle: Handle<T>) -> T {
        handle.read(&self.values)
    }

    /// Value by console name (the console, telemetry and the phone; code uses [`Self::get`]).
    pub fn by_name(&self, name: &str) -> Option<Value> {
        let (i, p) = find(name)?;
        self.values.get(i).map(|&bits| p.value_of(bits))
    }

    /// Changes a value, given by console name, after checking it and the whole set it makes.
    pub fn set(&mut self, name: &str, value: Value) -> Result<(), ParamError> {
        self.set_many(&[(name, value)])
    }

    /// Changes one value, named by its handle (see [`Self::apply`]).
    pub fn put<T: ParamType>(&mut self, handle: Handle<T>, value: T) -> Result<(), ParamError> {
        self.apply(&[handle.to(value)])
    }

    /// Changes several values given by console name at once (see [`Self::apply`]; code
    /// names them by handle and calls `apply`).
    pub fn set_many(&mut self, changes: &[(&str, Value)]) -> Result<(), ParamError> {
        let mut typed: heapless::Vec<Change, COUNT> = heapless::Vec::new();
        for &(name, value) in changes {
            let change = Change::by_name(name, value).ok_or(ParamError::Unknown)?;
            typed.push(change).map_err(|_| ParamError::Unparsable)?;
        }
        self.apply(&typed)
    }

    /// Changes several values at once (`handle.to(value)` each): each is range-checked, then
    /// the whole resulting set is validated; on any error nothing changes. Use it for
    /// changes that are only valid together (PWM and its rate, a bind's five `link.*` values).
    pub fn apply(&mut self, changes: &[Change]) -> Result<(), ParamError> {
        let mut candidate = self.clone();
        for change in changes {
            let p = PARAMS.get(change.index()).ok_or(ParamError::Unknown)?;
            let checked = p.check(change.value())?;
            let slot = candidate
                .values
                .get_mut(change.index())
                .ok_or(ParamError::Unknown)?;
            *slot = checked.to_bits();
        }
        candidate.check().map_err(ParamError::Invalid)?;
        *self = candidate;
        Ok(())
    }

    /// Changes a value given as console text.
    #[inline] // see `ParamText::parse`
    pub fn set_text(&mut self, name: &str, text: &str) -> Result<(), ParamError> {
        let (_, p) = find(name).ok_or(ParamError::Unknown)?;
        let value = p.parse(text)?;
        self.set(name, value)
    }

    /// Changes up to [`MAX_PAIRS`] values given as console text, `NAME VALUE NAME VALUE …`,
    /// together (see [`Settings::apply`]).
    #[inline] // see `ParamText::parse`
    pub fn set_text_pairs(&mut self, text: &str) -> Result<(), ParamError> {
        let mut changes: heapless::Vec<Change, MAX_PAIRS> = heapless::Vec::new();
        let mut words = text.split_ascii_whitespace();
        while let Some(name) = words.next() {
            let value_text = words.next().ok_or(ParamError::Unparsable)?;
            let (_, p) = find(name).ok_or(ParamError::Unknown)?;
            let value = p.parse(value_text)?;
            let change = Change::by_name(name, value).ok_or(ParamError::Unknown)?;
            changes.push(change).map_err(|_| ParamError::Unparsable)?;
        }
        self.apply(&changes)
    }

    /// Whether the whole set can run (every cross-setting rule).
    pub fn check(&self) -> Result<(), InvalidSettings> {
        validate(self).map(|_| ())
    }

    /// This set if it can run, else the factory set and why this one was refused (for the
    /// console and telemetry). What boot does with a stored set.
    pub fn or_defaults(self) -> (Self, Option<InvalidSettings>) {
        match self.check() {
            Ok(()) => (self, None),
            Err(e) => (Self::default(), Some(e)),
        }
    }

    /// (parameter, value) pairs in table order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static Param, Value)> + '_ {
        PARAMS
            .iter()
            .zip(self.values.iter())
            .map(|(p, &bits)| (p, p.value_of(bits)))
    }

    pub(crate) fn set_by_key(&mut self, key: u16, bits: u32) -> Result<(), ParamError> {
        let i = PARAMS
            .iter()
            .position(|p| p.key == key)
            .ok_or(ParamError::Unknown)?;
        let p = PARAMS.get(i).ok_or(ParamError::Unknown)?;
        let value = p.from_bits(bits)?;
        let slot = self.values.get_mut(i).ok_or(ParamError::Unknown)?;
        *slot = value.to_bits();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use telemetry::settings::handles;

    #[test]
    fn set_checks_ranges_and_choices() {
        let mut s = Settings::default();
        assert_eq!(s.get(handles::OUTPUT_RATE_HZ), 32_000);
        s.set_text("output.protocol", "oneshot125").unwrap();
        assert_eq!(s.get(handles::OUTPUT_PROTOCOL), 2);
        assert_eq!(
            s.set_text("output.protocol", "dshot"),
            Err(ParamError::Unparsable)
        );
        assert_eq!(
            s.set_text("pid.roll.kp", "2.5"),
            Err(ParamError::OutOfRange)
        );
        assert_eq!(
            s.set_text("pid.roll.kp", "NaN"),
            Err(ParamError::OutOfRange)
        );
        s.set_text("pid.roll.kp", "0.004").unwrap();
        assert_eq!(s.get(handles::PID_ROLL_KP), 0.004);
        assert_eq!(s.set_text("no.such", "1"), Err(ParamError::Unknown));
        // The schema's one spelling, in any letter case.
        s.set_text("link.protocol", "OpenLRS39").unwrap();
        assert_eq!(s.get(handles::LINK_PROTOCOL), 2);
        assert_eq!(
            s.set_text("link.protocol", "olrs38"),
            Err(ParamError::Unparsable)
        );
        s.set_text("link.rate", "f500").unwrap();
        assert_eq!(s.get(handles::LINK_RATE), 3);
        assert_eq!(
            s.set("battery.cells", Value::F32(1.0)),
            Err(ParamError::OutOfRange),
            "wrong kind"
        );
    }
}
