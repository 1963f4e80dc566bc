//! Settings by name and text (`rate=M100`, `input_timeout_ms=750`): the one place that maps
//! the words a person types (a host tool's `--module-set`, a console) onto [`Settings`]
//! fields, with the same ranges the record decoder enforces, so nothing typed can make a
//! set the module would refuse to load.
//!
//! `phrase` takes the binding phrase (spec §12: 1–64 printable bytes, white space at the
//! ends dropped; empty clears it) and stores only the key derived from it; `ble_pin` takes
//! six digits or `factory`.

use telemetry::link::key_for_phrase;

use super::{
    Band, INPUT_TIMEOUT_MS, InputProtocol, OutputProtocol, RateMode, Role, Settings,
    TELEMETRY_RATIOS,
};
use crate::hm10::at::Pin;
use crate::ppm::FailsafeOutput;

/// Every setting name, in record order.
pub const NAMES: [&str; 12] = [
    "role",
    "rate",
    "input",
    "output",
    "band",
    "tx_power",
    "failsafe",
    "bind_id",
    "input_timeout_ms",
    "telemetry_ratio",
    "phrase",
    "ble_pin",
];

/// Why a typed setting was refused (nothing changed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TextError {
    /// No setting by that name (see [`NAMES`]).
    Unknown,
    /// Not a number, or not one of the setting's words.
    Unparsable,
    /// A number outside the setting's range.
    OutOfRange,
    /// A binding phrase longer than 64 bytes or with a control character.
    BadPhrase,
}

impl core::fmt::Display for TextError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Unknown => "no such module setting",
            Self::Unparsable => "cannot read that value",
            Self::OutOfRange => "value out of range",
            Self::BadPhrase => "binding phrase: 1-64 printable bytes",
        })
    }
}

impl core::error::Error for TextError {}

/// The words each choice setting accepts (case-insensitive), for help texts.
pub fn choices(name: &str) -> &'static [&'static str] {
    match name {
        "role" => &["transmitter", "receiver"],
        "rate" => &["L50", "M100", "F250", "F500"],
        "input" => &["ppm", "crsf", "crsf115200", "crsf921600"],
        "output" => &["off", "crsf", "sport", "frsky_hub"],
        "band" => &["433", "868", "915", "ism433"],
        "failsafe" => &["hold_last", "stop_pulses"],
        _ => &[],
    }
}

/// The index of `text` among `words` (case-insensitive).
fn choice(text: &str, words: &[&str]) -> Result<usize, TextError> {
    words
        .iter()
        .position(|w| w.eq_ignore_ascii_case(text))
        .ok_or(TextError::Unparsable)
}

/// A whole number within `range`.
fn number(text: &str, range: core::ops::RangeInclusive<u32>) -> Result<u32, TextError> {
    let t = text.trim();
    let v = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16),
        None => t.parse(),
    }
    .map_err(|_| TextError::Unparsable)?;
    if range.contains(&v) {
        Ok(v)
    } else {
        Err(TextError::OutOfRange)
    }
}

impl Settings {
    /// Sets the field `name` (one of [`NAMES`]) from `text`; on an error nothing changes.
    /// Rates are the link's rate modes (`L50`, `M100`, `F250`, `F500`); the telemetry ratio
    /// one of [`TELEMETRY_RATIOS`].
    pub fn set_text(&mut self, name: &str, text: &str) -> Result<(), TextError> {
        let text = text.trim();
        let words = choices(name);
        match name {
            "role" => {
                self.role = [Role::Transmitter, Role::Receiver]
                    .get(choice(text, words)?)
                    .copied()
                    .ok_or(TextError::Unparsable)?;
            }
            "rate" => {
                self.rate = RateMode::ALL
                    .get(choice(text, words)?)
                    .copied()
                    .ok_or(TextError::Unparsable)?;
            }
            "input" => {
                self.input = [
                    InputProtocol::Ppm,
                    InputProtocol::Crsf,
                    InputProtocol::Crsf115200,
                    InputProtocol::Crsf921600,
                ]
                .get(choice(text, words)?)
                .copied()
                .ok_or(TextError::Unparsable)?;
            }
            "output" => {
                self.output = [
                    OutputProtocol::Off,
                    OutputProtocol::Crsf,
                    OutputProtocol::SPort,
                    OutputProtocol::FrskyHub,
                ]
                .get(choice(text, words)?)
                .copied()
                .ok_or(TextError::Unparsable)?;
            }
            "band" => {
                self.band = [Band::Mhz433, Band::Mhz868, Band::Mhz915, Band::Ism433]
                    .get(choice(text, words)?)
                    .copied()
                    .ok_or(TextError::Unparsable)?;
            }
            "failsafe" => {
                self.failsafe = [FailsafeOutput::HoldLast, FailsafeOutput::StopPulses]
                    .get(choice(text, words)?)
                    .copied()
                    .ok_or(TextError::Unparsable)?;
            }
            "tx_power" => {
                self.tx_power =
                    u8::try_from(number(text, 0..=7)?).map_err(|_| TextError::OutOfRange)?;
            }
            "bind_id" => self.bind_id = number(text, 0..=u32::MAX)?,
            "input_timeout_ms" => {
                let range =
                    u32::from(*INPUT_TIMEOUT_MS.start())..=u32::from(*INPUT_TIMEOUT_MS.end());
                self.input_timeout_ms =
                    u16::try_from(number(text, range)?).map_err(|_| TextError::OutOfRange)?;
            }
            "telemetry_ratio" => {
                let v = number(text, 0..=u32::from(u8::MAX))?;
                self.telemetry_ratio = TELEMETRY_RATIOS
                    .iter()
                    .copied()
                    .find(|r| u32::from(*r) == v)
                    .ok_or(TextError::OutOfRange)?;
            }
            "phrase" => {
                self.link_key = key_for_phrase(text).map_err(|_| TextError::BadPhrase)?;
            }
            "ble_pin" => {
                self.ble_pin = if text.eq_ignore_ascii_case("factory") {
                    None
                } else if text.len() == 6 && text.bytes().all(|b| b.is_ascii_digit()) {
                    Some(Pin::new(number(text, 0..=999_999)?).ok_or(TextError::OutOfRange)?)
                } else {
                    return Err(TextError::Unparsable);
                };
            }
            _ => return Err(TextError::Unknown),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_sets_its_field_and_the_record_still_loads() {
        let mut s = Settings::default();
        for (name, text) in [
            ("role", "Receiver"),
            ("rate", "m100"),
            ("input", "crsf921600"),
            ("output", "frsky_hub"),
            ("band", "ism433"),
            ("tx_power", "3"),
            ("failsafe", "hold_last"),
            ("bind_id", "0xDEADBEEF"),
            ("input_timeout_ms", "750"),
            ("telemetry_ratio", "16"),
            ("phrase", " correct horse battery staple "),
            ("ble_pin", "042917"),
        ] {
            s.set_text(name, text).unwrap();
        }
        assert_eq!(
            s,
            Settings {
                role: Role::Receiver,
                rate: RateMode::M100,
                input: InputProtocol::Crsf921600,
                output: OutputProtocol::FrskyHub,
                band: Band::Ism433,
                tx_power: 3,
                failsafe: FailsafeOutput::HoldLast,
                bind_id: 0xDEAD_BEEF,
                input_timeout_ms: 750,
                telemetry_ratio: 16,
                link_key: Some(telemetry::link::LinkKey::from_phrase(
                    "correct horse battery staple"
                )),
                ble_pin: Pin::new(42_917),
            }
        );
        assert_eq!(Settings::from_record(&s.to_record()), Ok(s));
        // "?" is a valid phrase; nothing else takes it.
        assert!(
            NAMES
                .iter()
                .filter(|n| **n != "phrase")
                .all(|n| s.clone().set_text(n, "?").is_err())
        );
        s.set_text("phrase", "").unwrap();
        assert_eq!(s.link_key, None, "an empty phrase clears it");
        s.set_text("ble_pin", "Factory").unwrap();
        assert_eq!(s.ble_pin, None);
    }

    #[test]
    fn nonsense_is_refused_and_changes_nothing() {
        let mut s = Settings::default();
        let cases = [
            ("colour", "red", TextError::Unknown),
            ("rate", "F1000", TextError::Unparsable),
            ("telemetry_ratio", "3", TextError::OutOfRange),
            ("telemetry_ratio", "256", TextError::OutOfRange),
            ("tx_power", "8", TextError::OutOfRange),
            ("tx_power", "-1", TextError::Unparsable),
            ("input_timeout_ms", "99", TextError::OutOfRange),
            ("input_timeout_ms", "2001", TextError::OutOfRange),
            ("bind_id", "4294967296", TextError::Unparsable),
            ("phrase", &"x".repeat(65), TextError::BadPhrase),
            ("phrase", "tab\tinside", TextError::BadPhrase),
            ("ble_pin", "12345", TextError::Unparsable),
            ("ble_pin", "1234567", TextError::Unparsable),
            ("ble_pin", "12a456", TextError::Unparsable),
        ];
        for (name, text, error) in cases {
            assert_eq!(s.set_text(name, text), Err(error), "{name}={text}");
            assert_eq!(s, Settings::default());
        }
    }
}
