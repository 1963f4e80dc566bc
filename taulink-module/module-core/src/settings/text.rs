//! Settings by name and text (`rate=M100`, `input_timeout_ms=750`): the words a person types
//! (a host tool's `--module-set`, a console) read through the settings table
//! (`super::table`: the schema's choice words and ranges, and what each field can take, as
//! the record decoder checks them), so nothing typed can make a set the module would refuse
//! to load. A value that leaves the whole set unusable
//! ([`Settings::validate`]: an OpenLRSng carrier or hop outside the band plan) is refused
//! too, except while several values are typed together (see [`Settings::set_text`]).
//!
//! `phrase` takes the binding phrase (spec §12.5: the strength rule of
//! `telemetry::link::check_phrase`, white space at the ends dropped; empty clears it) and
//! stores only its slow derivation under the module's salt (derived here at once: this path
//! is a host tool's or a console's); `plain` (`on`/`off`) is the explicit setting for an
//! unauthenticated link; `ble_pin` takes six digits or `factory`.

use telemetry::link::{PhraseSecret, check_phrase};
use telemetry::settings::{Kind, choice_index};

use super::Settings;
use super::table::by_name;
use crate::hm10::at::Pin;
use telemetry::settings::module::MODULE_PARAMS;

/// The settings typed as text that are no table row: the binding phrase (stored as its
/// derivation) and the HM-10 PIN.
pub const TEXT_ONLY: [&str; 2] = ["phrase", "ble_pin"];

/// Every setting name: the table's, in record order, then [`TEXT_ONLY`].
pub fn names() -> impl Iterator<Item = &'static str> {
    MODULE_PARAMS.iter().map(|p| p.name).chain(TEXT_ONLY)
}

/// Why a typed setting was refused (nothing changed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TextError {
    /// No setting by that name (see [`names`]).
    Unknown,
    /// Not a number, or not one of the setting's words.
    Unparsable,
    /// A number outside the setting's range.
    OutOfRange,
    /// The value is fine alone, but the set would not run (an OpenLRSng carrier or hop
    /// outside the band plan, OpenLRSng in the receiver role).
    Invalid,
    /// A binding phrase that breaks the rule (`telemetry::link::check_phrase`).
    BadPhrase,
}

impl core::fmt::Display for TextError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Unknown => "no such module setting",
            Self::Unparsable => "cannot read that value",
            Self::OutOfRange => "value out of range",
            Self::Invalid => "refused: the OpenLRSng link would leave the band plan",
            Self::BadPhrase => {
                "binding phrase: 12-64 printable bytes, 6 different characters, no famous example"
            }
        })
    }
}

impl core::error::Error for TextError {}

/// The words each choice setting accepts (case-insensitive), for help texts: the schema's
/// (`telemetry::settings::module`; the rate, band and air protocol are spelt as the flight
/// side spells them: `rate=F500` here is `link.rate F500` there).
pub fn choices(name: &str) -> &'static [&'static str] {
    match by_name(name).map(|(_, p)| p.kind) {
        Some(Kind::Choice(words)) => words,
        _ => &[],
    }
}

/// A whole number, decimal or `0x` hexadecimal.
fn number(text: &str) -> Result<u32, TextError> {
    let t = text.trim();
    match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16),
        None => t.parse(),
    }
    .map_err(|_| TextError::Unparsable)
}

impl Settings {
    /// Sets the setting `name` (one of [`names`]) from `text`; on an error nothing changes.
    /// Rates are the link's rate modes (`L50`, `M100`, `F250`, `F500`, `F700`); the telemetry
    /// ratio one of [`super::TELEMETRY_RATIOS`]. A change after which the set would not run
    /// ([`Settings::validate`]) is refused with [`TextError::Invalid`]; to change the band
    /// and the OpenLRSng carrier together, use [`Settings::set_text_unchecked`] for each and
    /// [`Settings::validate`] once.
    pub fn set_text(&mut self, name: &str, text: &str) -> Result<(), TextError> {
        let mut candidate = *self;
        candidate.set_text_unchecked(name, text)?;
        // Only a change that breaks a usable set is refused (a damaged one stays editable).
        if candidate.validate().is_err() && self.validate().is_ok() {
            return Err(TextError::Invalid);
        }
        *self = candidate;
        Ok(())
    }

    /// [`Settings::set_text`] without the whole-set check (ranges still apply): a choice by
    /// its word, a number within its row's range that the field can take.
    pub fn set_text_unchecked(&mut self, name: &str, text: &str) -> Result<(), TextError> {
        let text = text.trim();
        let Some((row, param)) = by_name(name) else {
            return self.set_text_only(name, text);
        };
        let value = match param.kind {
            Kind::Choice(words) => choice_index(words, text)
                .and_then(|i| u32::try_from(i).ok())
                .ok_or(TextError::Unparsable)?,
            Kind::U32 { .. } | Kind::F32 { .. } => number(text)?,
        };
        if row.assign(self, value) {
            Ok(())
        } else {
            Err(TextError::OutOfRange)
        }
    }

    /// The [`TEXT_ONLY`] settings: the phrase (spec §12.5's rule; empty clears it), the PIN
    /// (six digits, or `factory`).
    fn set_text_only(&mut self, name: &str, text: &str) -> Result<(), TextError> {
        match name {
            "phrase" => {
                self.phrase_prs = check_phrase(text)
                    .map_err(|_| TextError::BadPhrase)?
                    .map(|phrase| PhraseSecret::derive(phrase, self.phrase_salt).prs);
            }
            "ble_pin" if text.eq_ignore_ascii_case("factory") => self.ble_pin = None,
            "ble_pin" if text.len() == 6 && text.bytes().all(|b| b.is_ascii_digit()) => {
                self.ble_pin = Some(Pin::new(number(text)?).ok_or(TextError::OutOfRange)?);
            }
            "ble_pin" => return Err(TextError::Unparsable),
            _ => return Err(TextError::Unknown),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ppm::FailsafeOutput;
    use crate::settings::{Band, InputProtocol, LinkProtocol, OutputProtocol, RateMode, Role};
    use telemetry::settings::{BANDS, PROTOCOLS, RATES};

    /// The module reads the link's words as the flight side's schema spells them, each to
    /// the value at its place (the device tool's option of the same index).
    #[test]
    fn the_link_words_are_the_schemas_on_both_ends() {
        let mut s = Settings::default();
        for (i, word) in PROTOCOLS.iter().enumerate() {
            s.set_text("protocol", word).unwrap();
            assert_eq!(usize::from(s.protocol.code()), i, "{word}");
        }
        s.set_text("protocol", "taulink").unwrap();
        for (word, mode) in RATES.iter().zip(RateMode::ALL) {
            s.set_text("rate", word).unwrap();
            assert_eq!(s.rate, mode, "{word}");
        }
        let bands = [Band::Mhz433, Band::Mhz868, Band::Mhz915, Band::Ism433];
        for (word, band) in BANDS.iter().zip(bands) {
            s.set_text("band", word).unwrap();
            assert_eq!(s.band, band, "{word}");
        }
        assert_eq!(s.set_text("protocol", "olrs38"), Err(TextError::Unparsable));
    }

    #[test]
    fn every_name_sets_its_field_and_the_record_still_loads() {
        let mut s = Settings::default();
        for (name, text) in [
            ("role", "Receiver"),
            ("rate", "m100"),
            ("input", "crsf921600"),
            ("output", "frsky_hub"),
            ("band", "868"),
            ("tx_power", "3"),
            ("failsafe", "hold_last"),
            ("bind_id", "0xDEADBEEF"),
            ("input_timeout_ms", "750"),
            ("telemetry_ratio", "16"),
            ("model_match", "On"),
            ("olrs_profile", "125000"),
            ("olrs_channels", "16"),
            ("olrs_telemetry", "off"),
            ("olrs_frequency_hz", "866000000"),
            ("olrs_hop_seed", "77"),
            ("phrase", " amber kettle under the oak "),
            ("ble_pin", "042917"),
            ("plain", "on"),
            ("dynamic_power", "off"),
            // Last: OpenLRSng runs in the transmitter role only.
            ("role", "transmitter"),
            ("protocol", "OpenLRS39"),
        ] {
            s.set_text(name, text).unwrap();
        }
        assert_eq!(
            s,
            Settings {
                role: Role::Transmitter,
                rate: RateMode::M100,
                input: InputProtocol::Crsf921600,
                output: OutputProtocol::FrskyHub,
                band: Band::Mhz868,
                tx_power: 3,
                failsafe: FailsafeOutput::HoldLast,
                bind_id: 0xDEAD_BEEF,
                input_timeout_ms: 750,
                telemetry_ratio: 16,
                model_match: true,
                bound_models: 0,
                protocol: LinkProtocol::OpenLrs39,
                openlrs: super::super::OpenLrsSettings {
                    frequency_hz: 866_000_000,
                    profile: 4,
                    channel_mode: 6,
                    telemetry: false,
                    hop_seed: 77,
                },
                link_key: None,
                phrase_salt: [0; 8],
                phrase_prs: Some(
                    telemetry::link::PhraseSecret::derive("amber kettle under the oak", [0; 8]).prs
                ),
                plain: true,
                dynamic_power: false,
                ble_pin: Pin::new(42_917),
            }
        );
        assert!(s.validate().is_ok());
        assert_eq!(Settings::from_record(&s.to_record()), Ok(s));
        // Nothing takes "?".
        assert!(names().all(|n| s.clone().set_text(n, "?").is_err()));
        s.set_text("phrase", "").unwrap();
        assert_eq!(s.phrase_prs, None, "an empty phrase clears it");
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
            ("protocol", "openlrs", TextError::Unparsable),
            ("olrs_channels", "20", TextError::Unparsable),
            ("olrs_frequency_hz", "1000000000", TextError::OutOfRange),
            ("phrase", &"x".repeat(65), TextError::BadPhrase),
            ("phrase", "tab\tinside this phrase", TextError::BadPhrase),
            ("phrase", "too short", TextError::BadPhrase),
            (
                "phrase",
                "correct horse battery staple",
                TextError::BadPhrase,
            ),
            ("ble_pin", "12345", TextError::Unparsable),
            ("ble_pin", "1234567", TextError::Unparsable),
            ("ble_pin", "12a456", TextError::Unparsable),
        ];
        for (name, text, error) in cases {
            assert_eq!(s.set_text(name, text), Err(error), "{name}={text}");
            assert_eq!(s, Settings::default());
        }
        // OpenLRSng on the EU plan needs an 868 MHz carrier: typed one by one, the band
        // change alone is refused; typed together and checked once, it is taken.
        let mut s = Settings {
            protocol: LinkProtocol::OpenLrs38,
            ..Settings::default()
        };
        assert_eq!(
            s.set_text("olrs_frequency_hz", "868000000"),
            Err(TextError::Invalid)
        );
        // Inside OpenLRSng's 433 module range, outside the amateur band plan.
        assert_eq!(
            s.set_text("olrs_frequency_hz", "420000000"),
            Err(TextError::Invalid)
        );
        assert_eq!(s.openlrs.frequency_hz, 0);
        let mut both = s;
        both.set_text_unchecked("band", "868").unwrap();
        both.set_text_unchecked("olrs_frequency_hz", "0").unwrap();
        assert!(both.validate().is_ok());
        assert_eq!(s.set_text("role", "receiver"), Err(TextError::Invalid));
        assert_eq!(s.role, Role::Transmitter);
    }
}
