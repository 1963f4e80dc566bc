//! The module's binding phrase set from outside its text settings (spec §12.5): typed on the
//! radio in the device tool's "Bind Phrase" row (a CRSF STRING parameter), which is the
//! owner's deliberate act — the radio is physically the owner's — or proposed by the phone
//! over the HM-10 relay (`telemetry::module_record`), where it takes either the pilot's
//! confirmation on the radio ("Phone Phrase" command, showing the proposed key's
//! fingerprint) or a record signed under the module's current key. This module owns what
//! such a change may do and what the rows and the answers to the phone then say.
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

use taulink_handset::crsf::params::MAX_WRITE_LEN;
use telemetry::link::LinkKey;
use telemetry::link::auth::{PHRASE_MAX_BYTES, PhraseError, key_for_phrase};
use telemetry::module_record::{self, KeyAnswer, KeyOutcome, KeyRefusal, ModuleRecord};

use crate::params::Commands;

/// A proposal from the phone waits this many core ticks (`App::on_tick`, ≈ 10 Hz: about a
/// minute) for the pilot to start confirming it on the radio, then expires.
pub const PROPOSAL_TICKS: u16 = 600;

// A module record with its CRC fits one relay record.
const _: () = assert!(
    module_record::MAX_PAYLOAD_BYTES + crate::records::CRC_BYTES
        <= crate::hm10::relay::MAX_RECORD_LEN
);

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

/// What a key from the phone did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PhoneOutcome {
    /// The answer for the phone.
    pub answer: KeyAnswer,
    /// The key in force changed: restart the link and save.
    pub changed: bool,
}

/// The module's side of key changes from the phone: its session (random per boot), the
/// highest counter accepted in it, and how long a proposal still waits for the pilot. The
/// proposal itself sits in [`Commands::phone_key`], where the "Phone Phrase" row shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PhoneKeys {
    session: u32,
    highest: u32,
    ticks_left: u16,
}

impl PhoneKeys {
    /// A fresh session from a boot-time random number (one-way mixed: the session is public,
    /// the random number also seeds the link's nonces).
    pub fn new(random: u64) -> Self {
        // SplitMix64's finaliser.
        let mut z = random ^ 0x9E37_79B9_7F4A_7C15;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Self {
            session: (z >> 32) as u32,
            highest: 0,
            ticks_left: 0,
        }
    }

    /// The session nonce answers carry.
    pub fn session(&self) -> u32 {
        self.session
    }

    /// An answer with `outcome` about the key `about`.
    pub fn answer(&self, outcome: KeyOutcome, about: Option<LinkKey>) -> KeyAnswer {
        KeyAnswer {
            outcome,
            fingerprint: about.map(|k| k.fingerprint().0),
            session: self.session,
            counter: self.highest,
        }
    }

    /// A module record from the phone; `None` for records a phone does not send.
    pub fn on_record(
        &mut self,
        record: &ModuleRecord,
        link_key: &mut Option<LinkKey>,
        commands: &mut Commands,
    ) -> Option<PhoneOutcome> {
        let refuse = |keys: &Self, why: KeyRefusal, key: &Option<LinkKey>| PhoneOutcome {
            answer: keys.answer(KeyOutcome::Refused(why), *key),
            changed: false,
        };
        match record {
            ModuleRecord::KeyAnswer(_) => None,
            _ if commands.flight_armed => Some(refuse(self, KeyRefusal::Armed, link_key)),
            ModuleRecord::ProposeKey(bytes) => {
                let key = LinkKey::from_bytes(*bytes);
                if *link_key == Some(key) {
                    return Some(PhoneOutcome {
                        answer: self.answer(KeyOutcome::Applied, *link_key),
                        changed: false,
                    });
                }
                // A newer proposal replaces a waiting one (its phone hears nothing more).
                commands.phone_key = Some(key);
                commands.phone_confirming = false;
                commands.phone_result = None;
                self.ticks_left = PROPOSAL_TICKS;
                Some(PhoneOutcome {
                    answer: self.answer(KeyOutcome::AwaitingConfirmation, Some(key)),
                    changed: false,
                })
            }
            ModuleRecord::SignedKey(signed) => {
                let Some(current) = *link_key else {
                    return Some(refuse(self, KeyRefusal::NoPhrase, link_key));
                };
                let Some(key) = module_record::open(&current, self.session, signed) else {
                    return Some(refuse(self, KeyRefusal::NotAuthenticated, link_key));
                };
                if signed.counter <= self.highest {
                    return Some(refuse(self, KeyRefusal::Replayed, link_key));
                }
                self.highest = signed.counter;
                let (note, changed) = adopt(key, false, link_key);
                commands.phrase_note = Some(note);
                Some(PhoneOutcome {
                    answer: self.answer(KeyOutcome::Applied, *link_key),
                    changed,
                })
            }
        }
    }

    /// One core tick: a proposal nobody started confirming expires (the answer says so).
    pub fn on_tick(
        &mut self,
        link_key: Option<LinkKey>,
        commands: &mut Commands,
    ) -> Option<KeyAnswer> {
        if commands.phone_key.is_none() || commands.phone_confirming {
            return None;
        }
        self.ticks_left = self.ticks_left.saturating_sub(1);
        if self.ticks_left > 0 {
            return None;
        }
        commands.phone_key = None;
        Some(self.answer(KeyOutcome::Refused(KeyRefusal::Expired), link_key))
    }
}
