//! Who may change the flight side's settings over the link (spec §12.5): only the owner's
//! phone, proven by a tag under the key derived from the binding phrase
//! (`telemetry::change_auth`), with a counter above every one accepted in this boot's
//! session, and never while armed. Every refusal is answered with its reason and what a
//! fresh change must carry (`ChangeRefused`). Read-only telemetry needs no secret. The
//! console (a cable on the bench) stays the way to change settings without a phrase.

use telemetry::change_auth::ChangeKey;
use telemetry::link::LinkKey;
use telemetry::messages::{ChangeRefused, Message, RefuseReason, SettingChange, SignedChange};

use crate::report::apply_setting;
use crate::settings::Settings;

/// The flight side's answer to a change from the link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reply {
    /// Applied: the new value, echoed.
    Applied(SettingChange),
    /// Refused, with the reason, the session and the highest counter.
    Refused(ChangeRefused),
}

impl Reply {
    /// The message that answers the phone.
    pub fn message(self) -> Message {
        match self {
            Reply::Applied(c) => Message::SettingChange(c),
            Reply::Refused(r) => Message::ChangeRefused(r),
        }
    }
}

/// This boot's session and the highest counter accepted in it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChangeGate {
    session: u32,
    highest: u32,
}

impl ChangeGate {
    /// A gate for a boot whose session nonce is `session` (injected randomness: a session
    /// that repeats across boots would let an old recorded change through again).
    pub const fn new(session: u32) -> Self {
        Self {
            session,
            highest: 0,
        }
    }

    /// This boot's session nonce.
    pub fn session(&self) -> u32 {
        self.session
    }

    /// A message from the uplink stream: a change (signed or not) is checked and, if it
    /// passes, applied to `settings`; anything else is no change (`None`). `key` is the link
    /// key in force, `armed` whether the motors may turn.
    pub fn on_message(
        &mut self,
        message: &Message,
        settings: &mut Settings,
        key: Option<LinkKey>,
        armed: bool,
    ) -> Option<Reply> {
        let (id, signed) = match message {
            Message::SettingChange(c) => (c.id, None),
            Message::SignedChange(s) => (s.change.id, Some(s)),
            _ => return None,
        };
        Some(match self.check(signed, key, armed) {
            Err(reason) => self.refuse(id, reason),
            Ok(change) => match apply_setting(settings, change) {
                (Ok(()), Some(echo)) => Reply::Applied(echo),
                _ => self.refuse(id, RefuseReason::Invalid),
            },
        })
    }

    fn check(
        &mut self,
        signed: Option<&SignedChange>,
        key: Option<LinkKey>,
        armed: bool,
    ) -> Result<SettingChange, RefuseReason> {
        let Some(key) = key else {
            return Err(if armed {
                RefuseReason::Armed
            } else {
                RefuseReason::NoPhrase
            });
        };
        let signed = signed.ok_or(if armed {
            RefuseReason::Armed
        } else {
            RefuseReason::NotAuthenticated
        })?;
        if !ChangeKey::from_link_key(&key).verify(self.session, signed) {
            return Err(RefuseReason::NotAuthenticated);
        }
        if signed.counter <= self.highest {
            return Err(RefuseReason::Replayed);
        }
        // Used up whatever comes of it — a refused value, or a refusal because the quad is
        // armed: a recorded copy must never apply later in this boot (issue 30, finding 6).
        self.highest = signed.counter;
        if armed {
            return Err(RefuseReason::Armed);
        }
        Ok(signed.change)
    }

    fn refuse(&self, id: u16, reason: RefuseReason) -> Reply {
        Reply::Refused(ChangeRefused {
            id,
            reason,
            session: self.session,
            counter: self.highest,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::f32_value;
    use crate::settings::{PARAMS, handles};
    use telemetry::change_auth::{ChangeKey, Signer};

    const SESSION: u32 = 0x5E55_1017;

    fn descent() -> SettingChange {
        let id = PARAMS
            .iter()
            .position(|p| p.name == "failsafe.descent_mps")
            .unwrap() as u16;
        SettingChange {
            id,
            value: f32_value(0.9),
        }
    }

    /// A phone that has learnt this boot's session from a first refusal, as a real one does.
    fn phone_in_session() -> Signer {
        let mut phone = Signer::new(ChangeKey::from_link_key(&key()));
        phone.on_refused(&ChangeRefused {
            id: 0,
            reason: RefuseReason::NotAuthenticated,
            session: SESSION,
            counter: 0,
        });
        phone
    }

    fn key() -> LinkKey {
        LinkKey::from_bytes([0x6B; 16])
    }

    fn refused(reply: Option<Reply>) -> RefuseReason {
        match reply {
            Some(Reply::Refused(r)) => {
                assert_eq!(r.session, SESSION, "every refusal names the session");
                r.reason
            }
            other => panic!("refused expected, got {other:?}"),
        }
    }

    #[test]
    fn only_a_signed_fresh_change_while_disarmed_is_applied() {
        let mut gate = ChangeGate::new(SESSION);
        let mut settings = Settings::default();
        let before = settings.clone();
        let mut phone = Signer::new(ChangeKey::from_link_key(&key()));
        // Unsigned (what every phone sent before): refused, nothing changes.
        let plain = Message::SettingChange(descent());
        let r = refused(gate.on_message(&plain, &mut settings, Some(key()), false));
        assert_eq!(r, RefuseReason::NotAuthenticated);
        assert_eq!(settings, before);
        // Signed without the session: refused; the phone learns it and signs again.
        let Some(Reply::Refused(answer)) = gate.on_message(
            &Message::SignedChange(phone.sign(descent())),
            &mut settings,
            Some(key()),
            false,
        ) else {
            panic!("refused")
        };
        assert!(phone.on_refused(&answer));
        let good = Message::SignedChange(phone.sign(descent()));
        assert_eq!(
            gate.on_message(&good, &mut settings, Some(key()), true)
                .map(|r| refused(Some(r))),
            Some(RefuseReason::Armed)
        );
        assert_eq!(settings, before, "never while armed");
        // That one is used up; the phone signs the next.
        let good = Message::SignedChange(phone.sign(descent()));
        assert_eq!(
            gate.on_message(&good, &mut settings, Some(key()), false),
            Some(Reply::Applied(descent()))
        );
        assert_eq!(settings.get(handles::FAILSAFE_DESCENT_MPS), 0.9);
        // The same frame again: a replay.
        let mut again = settings.clone();
        assert_eq!(
            refused(gate.on_message(&good, &mut again, Some(key()), false)),
            RefuseReason::Replayed
        );
        // Another phrase, or none on the flight side.
        let mut stranger = Signer::new(ChangeKey::from_link_key(&LinkKey::from_bytes([1; 16])));
        stranger.on_refused(&answer);
        let forged = Message::SignedChange(stranger.sign(descent()));
        assert_eq!(
            refused(gate.on_message(&forged, &mut again, Some(key()), false)),
            RefuseReason::NotAuthenticated
        );
        assert_eq!(
            refused(gate.on_message(&good, &mut again, None, false)),
            RefuseReason::NoPhrase
        );
        assert_eq!(again, settings);
        // A change recorded in this session fails in the next boot's session.
        let mut next_boot = ChangeGate::new(SESSION ^ 1);
        let mut fresh = Settings::default();
        let Some(Reply::Refused(r)) = next_boot.on_message(&good, &mut fresh, Some(key()), false)
        else {
            panic!("refused");
        };
        assert_eq!(r.reason, RefuseReason::NotAuthenticated);
        assert_eq!(fresh, Settings::default());
        // Other messages are no change.
        assert_eq!(
            gate.on_message(
                &Message::Cells(telemetry::messages::Cells { count: 3 }),
                &mut again,
                Some(key()),
                false
            ),
            None
        );
    }

    /// Issue 30, finding 6: a signed change refused because the quad was armed was not used
    /// up (the armed check came before the counter was recorded), so its recorded copy
    /// applied after disarming, in the same boot.
    #[test]
    fn a_signed_change_refused_while_armed_is_used_up() {
        let mut gate = ChangeGate::new(SESSION);
        let mut settings = Settings::default();
        let mut phone = phone_in_session();
        let signed = Message::SignedChange(phone.sign(descent()));
        assert_eq!(
            refused(gate.on_message(&signed, &mut settings, Some(key()), true)),
            RefuseReason::Armed
        );
        // Disarmed, later in the same boot: the recording is a replay.
        assert_eq!(
            refused(gate.on_message(&signed, &mut settings, Some(key()), false)),
            RefuseReason::Replayed
        );
        assert_eq!(settings, Settings::default());
        // A forgery while armed uses nothing up: the phone's next change still applies.
        let mut forged = phone.sign(descent());
        forged.tag[0] ^= 1;
        assert_eq!(
            refused(gate.on_message(
                &Message::SignedChange(forged),
                &mut settings,
                Some(key()),
                true
            )),
            RefuseReason::NotAuthenticated
        );
        let next = Message::SignedChange(phone.sign(descent()));
        assert_eq!(
            gate.on_message(&next, &mut settings, Some(key()), false),
            Some(Reply::Applied(descent()))
        );
    }

    #[test]
    fn an_out_of_range_value_is_refused_as_invalid_and_uses_its_counter() {
        let mut gate = ChangeGate::new(SESSION);
        let mut settings = Settings::default();
        let mut phone = phone_in_session();
        let bad = SettingChange {
            value: f32_value(99.0),
            ..descent()
        };
        let signed = Message::SignedChange(phone.sign(bad));
        assert_eq!(
            refused(gate.on_message(&signed, &mut settings, Some(key()), false)),
            RefuseReason::Invalid
        );
        assert_eq!(settings, Settings::default());
        assert_eq!(
            refused(gate.on_message(&signed, &mut settings, Some(key()), false)),
            RefuseReason::Replayed
        );
    }
}
