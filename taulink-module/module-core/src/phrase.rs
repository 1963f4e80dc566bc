//! The module's binding phrase and the phone's access to it (spec §12.1, §12.5).
//!
//! **The phrase** is typed on the radio in the device tool's "Bind Phrase" row (a CRSF
//! STRING parameter; the radio is physically the owner's, so a write is the owner's act), set
//! through the text settings (`phrase=TEXT`), or set by a phone that proved the current one.
//! It must meet the rule every end applies (`telemetry::link::check_phrase`); only its slow,
//! salted derivation is stored (`Settings::phrase_prs`), never the text. The derivation takes
//! ≈ 2 s of the nRF52840, so a write from the radio starts a [`PhraseJob`] the firmware runs
//! an iteration at a time; the "Link Key" row says "deriving" meanwhile. A new phrase does
//! not change the running link (its key was agreed at bind): it is what the next bind and
//! the next phone exchange run on. Refused, and nothing changes: while the quad is armed
//! (the flight side's last `ArmState`, kept after a link loss), an empty text (the radio's
//! editor commits the text when the pilot backs out; clearing is `phrase=`), and a phrase
//! that breaks the rule.
//!
//! **The phone** ([`PhoneAccess`]) runs CPace with the module on the stored derivation
//! (`telemetry::module_record`): a right confirmation gets it the change key of the flight
//! link (sealed) and a session to set a new phrase in; every exchange costs the module a
//! scalar multiplication, so a new one is answered at most every [`HELLO_TICKS`] core ticks,
//! and after [`PHONE_FAILURES`] wrong confirmations the module refuses every exchange until
//! it restarts (an online guesser gets that many guesses per power cycle). Nothing is taken
//! while the quad is armed, and a phrase refused for that is used up.

use taulink_handset::crsf::params::MAX_WRITE_LEN;
use telemetry::change_auth::ChangeKey;
use telemetry::link::phrase::{Derivation, PHRASE_MAX_BYTES};
use telemetry::link::{PhraseError, PhraseSecret, check_phrase};
use telemetry::module_record::{
    self, Answer, ModuleExchange, ModuleRecord, ModuleSession, Outcome, PHONE_FAILURES, Refusal,
};

use crate::settings::Settings;

/// Core ticks (`App::on_tick`, ≈ 10 Hz) between two phone exchanges the module starts.
pub const HELLO_TICKS: u8 = 5;

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

/// What the last attempt to set the phrase from outside did (the "Link Key" row says it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PhraseNote {
    /// The new phrase is in force (for the next bind and phone exchange).
    Set,
    /// Its derivation is running.
    Deriving,
    /// Refused: the quad is armed.
    Armed,
    /// Refused: the text was empty (the phrase is kept).
    Empty,
    /// Refused: it breaks the strength rule or is not printable UTF-8.
    Refused(PhraseError),
}

impl PhraseNote {
    /// The row text for a note; `None` when the row shows the key.
    pub fn text(self) -> Option<&'static str> {
        match self {
            PhraseNote::Set => None,
            PhraseNote::Deriving => Some("deriving phrase..."),
            PhraseNote::Armed => Some("refused: quad armed"),
            PhraseNote::Empty => Some("empty: phrase kept"),
            PhraseNote::Refused(PhraseError::TooShort) => Some("refused: < 12 chars"),
            PhraseNote::Refused(PhraseError::TooSimple) => Some("refused: too simple"),
            PhraseNote::Refused(PhraseError::Famous) => Some("refused: famous phrase"),
            PhraseNote::Refused(PhraseError::TooLong) => Some("refused: too long"),
            PhraseNote::Refused(PhraseError::NotPrintable) => Some("refused: bad character"),
        }
    }
}

/// The phrase a STRING write from the radio asks for: its text up to the first NUL (the
/// radio ends it with one; a write without is taken whole), checked.
pub fn phrase_from_write(value: &[u8]) -> Result<&str, PhraseNote> {
    let text = value.split(|b| *b == 0).next().unwrap_or(&[]);
    let text =
        core::str::from_utf8(text).map_err(|_| PhraseNote::Refused(PhraseError::NotPrintable))?;
    match check_phrase(text) {
        Ok(Some(phrase)) => Ok(phrase),
        Ok(None) => Err(PhraseNote::Empty),
        Err(e) => Err(PhraseNote::Refused(e)),
    }
}

/// A phrase's derivation the firmware runs in steps, then hands to the settings.
#[derive(Debug, Clone)]
pub struct PhraseJob(Derivation);

impl PhraseJob {
    /// The derivation of `phrase` (checked) under the module's salt.
    pub fn new(phrase: &str, settings: &Settings) -> Self {
        Self(Derivation::new(phrase, settings.phrase_salt))
    }

    /// Runs up to `iterations`; the derivation once done.
    pub fn step(&mut self, iterations: u32) -> Option<PhraseSecret> {
        self.0.step(iterations)
    }
}

/// What a phone record did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PhoneReply {
    /// The record to answer with.
    pub reply: ModuleRecord,
    /// The stored phrase changed: save the settings.
    pub changed: bool,
}

/// The module's side of the phone exchanges.
#[derive(Debug, Default)]
pub struct PhoneAccess {
    /// The exchange waiting for the phone's response.
    exchange: Option<ModuleExchange>,
    /// The confirmed session, for new phrases.
    session: Option<ModuleSession>,
    /// Wrong confirmations since the module started.
    failures: u8,
    /// Ticks until the next exchange may start.
    cooldown: u8,
}

impl PhoneAccess {
    /// One core tick.
    pub fn on_tick(&mut self) {
        self.cooldown = self.cooldown.saturating_sub(1);
    }

    /// Wrong confirmations since the module started.
    pub fn failures(&self) -> u8 {
        self.failures
    }

    /// A record from the phone, with the settings, whether the quad is `armed`, the change
    /// key of the flight link (`None` without a keyed link) and `random` (32 bytes for a
    /// new exchange). `None`: nothing to answer (a record phones do not send, or an
    /// exchange asked for too soon after the last).
    pub fn on_record(
        &mut self,
        record: &ModuleRecord,
        settings: &mut Settings,
        armed: bool,
        change_key: Option<ChangeKey>,
        random: impl FnOnce() -> [u8; 32],
    ) -> Option<PhoneReply> {
        let answer = |outcome: Outcome, counter: u32| PhoneReply {
            reply: ModuleRecord::Answer(Answer { outcome, counter }),
            changed: false,
        };
        let refuse = |why: Refusal, counter: u32| answer(Outcome::Refused(why), counter);
        let counter = self.session.map_or(0, |s| s.highest());
        match record {
            ModuleRecord::Hello if self.failures >= PHONE_FAILURES => {
                Some(refuse(Refusal::Locked, counter))
            }
            ModuleRecord::Hello => {
                let Some(secret) = settings.phrase() else {
                    return Some(refuse(Refusal::NoPhrase, counter));
                };
                if self.cooldown > 0 {
                    return None;
                }
                self.cooldown = HELLO_TICKS;
                let exchange = ModuleExchange::new(&secret, &random());
                let challenge = exchange.challenge();
                self.exchange = Some(exchange);
                Some(PhoneReply {
                    reply: ModuleRecord::Challenge(challenge),
                    changed: false,
                })
            }
            ModuleRecord::Response(response) => {
                let Some(exchange) = self.exchange.take() else {
                    return Some(refuse(Refusal::NoSession, counter));
                };
                match exchange.respond(response, change_key.as_ref()) {
                    Some((session, granted)) => {
                        self.session = Some(session);
                        Some(PhoneReply {
                            reply: ModuleRecord::Granted(granted),
                            changed: false,
                        })
                    }
                    None => {
                        self.failures = self.failures.saturating_add(1);
                        Some(refuse(Refusal::NotAuthenticated, counter))
                    }
                }
            }
            ModuleRecord::SetPhrase(set) => {
                let Some(session) = self.session.as_mut() else {
                    return Some(refuse(Refusal::NoSession, counter));
                };
                // Verified and used up first: a copy refused while armed never applies later.
                let prs = match session.open(set) {
                    Ok(prs) => prs,
                    Err(why) => return Some(refuse(why, session.highest())),
                };
                let counter = session.highest();
                if armed {
                    return Some(refuse(Refusal::Armed, counter));
                }
                let changed = settings.phrase_prs != Some(prs);
                settings.phrase_prs = Some(prs);
                Some(PhoneReply {
                    changed,
                    ..answer(Outcome::Applied, counter)
                })
            }
            ModuleRecord::Challenge(_)
            | ModuleRecord::Granted(_)
            | ModuleRecord::Answer(_)
            | ModuleRecord::LinkSecurity(_) => None,
        }
    }
}
