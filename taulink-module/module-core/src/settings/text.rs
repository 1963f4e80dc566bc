//! Settings by name and text (`rate=M100`, `input_timeout_ms=750`): the one place that maps
//! the words a person types (a host tool's `--module-set`, a console) onto [`Settings`]
//! fields, with the same ranges the record decoder enforces, so nothing typed can make a
//! set the module would refuse to load. A value that leaves the whole set unusable
//! ([`Settings::validate`]: an OpenLRSng carrier or hop outside the band plan) is refused
//! too, except while several values are typed together (see [`Settings::set_text`]).
//!
//! `phrase` takes the binding phrase (spec §12.5: the strength rule of
//! `telemetry::link::check_phrase`, white space at the ends dropped; empty clears it) and
//! stores only its slow derivation under the module's salt (derived here at once: this path
//! is a host tool's or a console's); `plain` (`on`/`off`) is the explicit setting for an
//! unauthenticated link; `ble_pin` takes six digits or `factory`.

use telemetry::link::{PhraseSecret, check_phrase};
use telemetry::settings::{BANDS, PROTOCOLS, RATES, choice_index};

use super::openlrs::CHANNEL_MODES;
use super::{
    Band, INPUT_TIMEOUT_MS, InputProtocol, LinkProtocol, OutputProtocol, RateMode, Role, Settings,
    TELEMETRY_RATIOS,
};
use crate::hm10::at::Pin;
use crate::ppm::FailsafeOutput;

/// Every setting name, in record order.
pub const NAMES: [&str; 20] = [
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
    "model_match",
    "protocol",
    "olrs_profile",
    "olrs_channels",
    "olrs_telemetry",
    "olrs_frequency_hz",
    "olrs_hop_seed",
    "phrase",
    "ble_pin",
    "plain",
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

/// The words each choice setting accepts (case-insensitive), for help texts. The rate, band
/// and air protocol are the link's and spelt as the flight side spells them
/// (`telemetry::settings`: `rate=F500` here is `link.rate F500` there).
pub fn choices(name: &str) -> &'static [&'static str] {
    match name {
        "role" => &["transmitter", "receiver"],
        "rate" => RATES,
        "input" => &["ppm", "crsf", "crsf115200", "crsf921600"],
        "output" => &["off", "crsf", "sport", "frsky_hub"],
        "band" => BANDS,
        "failsafe" => &["hold_last", "stop_pulses"],
        "model_match" | "plain" => &["off", "on"],
        "protocol" => PROTOCOLS,
        "olrs_profile" => &["4800", "9600", "19200", "57600", "125000"],
        "olrs_channels" => &["4+4", "8", "8+4", "12", "12+4", "16"],
        "olrs_telemetry" => &["off", "on"],
        _ => &[],
    }
}

/// The index of `text` among `words` (case-insensitive, as every end reads choice words).
fn choice(text: &str, words: &[&str]) -> Result<usize, TextError> {
    choice_index(words, text).ok_or(TextError::Unparsable)
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
    /// Rates are the link's rate modes (`L50`, `M100`, `F250`, `F500`, `F700`); the telemetry ratio
    /// one of [`TELEMETRY_RATIOS`]. A change after which the set would not run
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

    /// [`Settings::set_text`] without the whole-set check (ranges still apply).
    pub fn set_text_unchecked(&mut self, name: &str, text: &str) -> Result<(), TextError> {
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
            "model_match" => self.model_match = choice(text, words)? == 1,
            "protocol" => {
                self.protocol = [
                    LinkProtocol::TauLink,
                    LinkProtocol::OpenLrs38,
                    LinkProtocol::OpenLrs39,
                ]
                .get(choice(text, words)?)
                .copied()
                .ok_or(TextError::Unparsable)?;
            }
            "olrs_profile" => {
                self.openlrs.profile =
                    u8::try_from(choice(text, words)?).map_err(|_| TextError::Unparsable)?;
            }
            "olrs_channels" => {
                let index =
                    u8::try_from(choice(text, words)?).map_err(|_| TextError::Unparsable)?;
                self.openlrs.channel_mode = CHANNEL_MODES.start() + index;
            }
            "olrs_telemetry" => self.openlrs.telemetry = choice(text, words)? == 1,
            "olrs_frequency_hz" => {
                let hz = number(text, 0..=u32::MAX)?;
                if !super::openlrs::carrier_in_range(hz) {
                    return Err(TextError::OutOfRange);
                }
                self.openlrs.frequency_hz = hz;
            }
            "olrs_hop_seed" => self.openlrs.hop_seed = number(text, 0..=u32::MAX)?,
            "phrase" => {
                self.phrase_prs = check_phrase(text)
                    .map_err(|_| TextError::BadPhrase)?
                    .map(|phrase| PhraseSecret::derive(phrase, self.phrase_salt).prs);
            }
            "plain" => self.plain = choice(text, words)? == 1,
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
                ble_pin: Pin::new(42_917),
            }
        );
        assert!(s.validate().is_ok());
        assert_eq!(Settings::from_record(&s.to_record()), Ok(s));
        // Nothing takes "?".
        assert!(NAMES.iter().all(|n| s.clone().set_text(n, "?").is_err()));
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
