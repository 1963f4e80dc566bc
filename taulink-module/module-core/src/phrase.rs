//! The module's binding phrase set from outside its text settings (spec §12.5): typed on the
//! radio in the device tool's "Bind Phrase" row (a CRSF STRING parameter), which is the
//! owner's deliberate act — the radio is physically the owner's. This module owns what such
//! a write may do and what the rows then say.
//!
//! Rules, the same as every other path (`telemetry::link::key_for_phrase`): white space at
//! either end is dropped, at most 64 bytes of printable UTF-8 remain (the radio's write frame
//! holds 56 of them, [`HANDSET_PHRASE_MAX`]). Only the key is stored, never the text; the
//! "Phrase Key" row shows its fingerprint afterwards. Refused, and nothing changes:
//! * while the quad is armed, as far as the module knows from the flight side's `ArmState`
//!   telemetry — the last state heard counts, also after the link dropped (an armed quad
//!   out of range may still be flying its failsafe, and a new key would keep it from ever
//!   hearing this module again);
//! * an empty text: the radio's editor commits whatever is in it when the pilot backs out,
//!   so an empty write is far more likely a slip than a wish to fly unauthenticated (the
//!   phrase is cleared through the text settings, `phrase=`).

use telemetry::handset::crsf::params::MAX_WRITE_LEN;
use telemetry::link::LinkKey;
use telemetry::link::auth::{PHRASE_MAX_BYTES, PhraseError, key_for_phrase};

/// Longest phrase the radio can write: a PARAMETER_WRITE holds [`MAX_WRITE_LEN`] value bytes,
/// the text and its NUL.
pub const HANDSET_PHRASE_MAX: u8 = {
    let room = MAX_WRITE_LEN - 1;
    let max = if room < PHRASE_MAX_BYTES {
        room
    } else {
        PHRASE_MAX_BYTES
    };
    if max > u8::MAX as usize {
        u8::MAX
    } else {
        max as u8
    }
};

/// What the last attempt to set the phrase from outside did (the "Phrase Key" row says it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PhraseNote {
    /// A new key is in force (the link restarted with it).
    Set,
    /// The phrase gave the key already in force.
    Unchanged,
    /// Refused: the quad is armed.
    Armed,
    /// Refused: the text was empty (the phrase is kept).
    Empty,
    /// Refused: longer than 64 bytes.
    TooLong,
    /// Refused: a control character or bytes that are no UTF-8.
    NotPrintable,
}

impl PhraseNote {
    /// The row text for a refusal; `None` when the row shows the fingerprint.
    pub fn refusal(self) -> Option<&'static str> {
        match self {
            PhraseNote::Set | PhraseNote::Unchanged => None,
            PhraseNote::Armed => Some("refused: quad armed"),
            PhraseNote::Empty => Some("empty: phrase kept"),
            PhraseNote::TooLong => Some("refused: too long"),
            PhraseNote::NotPrintable => Some("refused: bad character"),
        }
    }
}

/// The key a STRING write from the radio asks for: its text up to the first NUL (the radio
/// ends it with one; a write without is taken whole).
pub fn key_from_write(value: &[u8]) -> Result<LinkKey, PhraseNote> {
    let text = value.split(|b| *b == 0).next().unwrap_or(&[]);
    let text = core::str::from_utf8(text).map_err(|_| PhraseNote::NotPrintable)?;
    match key_for_phrase(text) {
        Ok(Some(key)) => Ok(key),
        Ok(None) => Err(PhraseNote::Empty),
        Err(PhraseError::TooLong) => Err(PhraseNote::TooLong),
        Err(PhraseError::NotPrintable) => Err(PhraseNote::NotPrintable),
    }
}

/// Puts `key` in force unless the quad is `armed`: the note for the row, and whether the
/// key changed (the link must restart and the set be saved).
pub fn adopt(key: LinkKey, armed: bool, link_key: &mut Option<LinkKey>) -> (PhraseNote, bool) {
    if armed {
        (PhraseNote::Armed, false)
    } else if *link_key == Some(key) {
        (PhraseNote::Unchanged, false)
    } else {
        *link_key = Some(key);
        (PhraseNote::Set, true)
    }
}
