//! Records between the phone and the TauLink module itself on the HM-10 relay (spec §12.5):
//! the phone proves the binding phrase to the module with CPace (no value on BLE lets a
//! guesser test a phrase offline), and over the session key that gives it receives the
//! change key of the flight side's settings, sealed, and may set a new phrase. No key ever
//! crosses BLE in the clear. Every other phone record goes on to the flight side unread;
//! these stop at the module.
//!
//! **Wire format.** Framed like every relay record (`COBS(payload ‖ crc16_be) ‖ 0x00`,
//! [`crate::framing`]); the payload is [`MARKER`], [`VERSION`], then the postcard encoding of a
//! [`ModuleRecord`]. A telemetry [`crate::messages::Message`] starts with its postcard variant
//! number, a one-byte varint below 0x80 for any message set of fewer than 128 variants, so no
//! message starts with 0xA5: the module tells the two apart by the first byte. A record of
//! another version is refused by [`decode`]; version 1 (a key proposed in the clear, or
//! sealed under a pad that could repeat) is no longer read.
//!
//! **The exchange.** Phone `Hello` → module `Challenge { salt, session, share }` (CPace,
//! module the initiator, on its stored phrase derivation, [`crate::link::PhraseSecret`]) →
//! phone `Response { share, tag }` (its share and its confirmation) → module `Granted { tag,
//! change_key }` (its confirmation and the change key sealed) or an [`Answer`] refusing.
//! With the session key the phone then sends `SetPhrase { counter, sealed, tag }`: a new
//! phrase's derivation under the module's salt, sealed with a pad of the session key and
//! counter (a fresh session key every exchange: no pad repeats) and tagged; the module
//! takes it once per counter, never while the quad is armed. Every refusal says why; the
//! module allows [`PHONE_FAILURES`] wrong confirmations per boot, then refuses every
//! exchange until it restarts (an online guesser gets that many guesses per power cycle).

use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

use crate::change_auth::ChangeKey;
use crate::link::auth::KEY_BYTES;
use crate::link::pake::{Exchange, Role, SHARE_BYTES, SessionKey, tags_equal};
use crate::link::phrase::{PRS_BYTES, PhraseSecret, SALT_BYTES};

/// First payload byte of every module record (never the first byte of a message).
pub const MARKER: u8 = 0xA5;
/// The record format's version (the second payload byte).
pub const VERSION: u8 = 2;
/// Largest payload of a module record.
pub const MAX_PAYLOAD_BYTES: usize = 2 + ModuleRecord::POSTCARD_MAX_SIZE;
/// Wrong confirmations a module takes from phones per boot before it refuses every
/// exchange ([`Refusal::Locked`]).
pub const PHONE_FAILURES: u8 = 5;
/// Bytes of a confirmation tag.
pub const TAG_BYTES: usize = 16;

/// The CPace channel identifier of phone exchanges.
const PHONE_CI: &[u8] = b"TauLink/2 phone";
const LABEL_PHONE_TAG: &[u8] = b"TauLink/2 phone confirms";
const LABEL_MODULE_TAG: &[u8] = b"TauLink/2 module confirms";
const LABEL_CHANGE_KEY: &[u8] = b"TauLink/2 change-key wrap";
const LABEL_PHRASE_PAD: &[u8] = b"TauLink/2 phrase wrap";
const LABEL_PHRASE_TAG: &[u8] = b"TauLink/2 phrase tag";

/// Why the module refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Refusal {
    /// The quad is armed (as far as the module heard): no phrase change in flight.
    Armed,
    /// The confirmation or tag does not verify (another phrase, a forgery).
    NotAuthenticated,
    /// The counter is not above the highest accepted in this session (a replay).
    Replayed,
    /// The module has no phrase: set the first one on the radio.
    NoPhrase,
    /// No exchange under way (a response or phrase without a session).
    NoSession,
    /// Too many wrong confirmations since the module started: restart it.
    Locked,
    /// The phrase's derivation would not be a valid one (never sent by the ground station).
    Invalid,
}

/// What became of a phone's record.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Outcome {
    /// Taken (the new phrase is in force and saved).
    Applied,
    /// Not taken.
    Refused(Refusal),
}

/// The module's answer to a record it did not answer with its own kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Answer {
    /// What happened.
    pub outcome: Outcome,
    /// The highest counter the module accepted in the session (sign with a greater one).
    pub counter: u32,
}

/// The module's side of the exchange: its salt, session and share.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Challenge {
    /// The salt of the module's phrase derivation.
    pub salt: [u8; SALT_BYTES],
    /// Random per exchange: the CPace session.
    pub session: [u8; 8],
    /// The module's CPace share.
    pub share: [u8; SHARE_BYTES],
}

/// The phone's share and confirmation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Response {
    /// The phone's CPace share.
    pub share: [u8; SHARE_BYTES],
    /// Its confirmation of the session key.
    pub tag: [u8; TAG_BYTES],
}

/// The module's confirmation and the change key, sealed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Granted {
    /// The module's confirmation of the session key.
    pub tag: [u8; TAG_BYTES],
    /// The change key of the flight side's settings ([`ChangeKey`]), sealed; `None` while
    /// the module has no keyed link (nothing to change on the flight side yet).
    pub change_key: Option<[u8; KEY_BYTES]>,
}

/// A new phrase's derivation for the module, sealed and tagged under the session key.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SetPhrase {
    /// Above every counter the module accepted in the session.
    pub counter: u32,
    /// The derivation under the module's salt, sealed with the session's pad of `counter`.
    pub sealed: [u8; PRS_BYTES],
    /// Tag over counter and sealed bytes.
    pub tag: [u8; TAG_BYTES],
}

/// Everything module-addressed on the relay.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModuleRecord {
    /// Phone → module: start an exchange.
    Hello,
    /// Module → phone: the module's half.
    Challenge(Challenge),
    /// Phone → module: the phone's half.
    Response(Response),
    /// Module → phone: the exchange confirmed, the change key.
    Granted(Granted),
    /// Phone → module: a new phrase.
    SetPhrase(SetPhrase),
    /// Module → phone: an outcome.
    Answer(Answer),
    /// Module → phone: authentication failures of the air link, both ends (spec §12.2).
    LinkSecurity(LinkSecurity),
}

/// Tag failures of the air link as the module knows them, for the phone (spec §12.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkSecurity {
    /// Downlinks whose tag failed at the module since it started.
    pub tag_failures_down: u32,
    /// Uplinks whose tag failed at the flight side (its last report).
    pub tag_failures_up: u32,
    /// Either end's failures run above what noise explains.
    pub alert: bool,
}

/// Why a payload is no module record this firmware reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// It does not start with [`MARKER`] (a message for the flight side).
    NotModule,
    /// Another format version.
    Version(u8),
    /// The postcard body does not decode.
    Malformed,
}

/// Whether a record payload is addressed to the module.
pub fn is_module_payload(payload: &[u8]) -> bool {
    payload.first() == Some(&MARKER)
}

/// The record in `payload` (CRC already checked).
pub fn decode(payload: &[u8]) -> Result<ModuleRecord, DecodeError> {
    match payload {
        [MARKER, VERSION, body @ ..] => {
            postcard::from_bytes(body).map_err(|_| DecodeError::Malformed)
        }
        [MARKER, version, ..] => Err(DecodeError::Version(*version)),
        [MARKER] => Err(DecodeError::Malformed),
        _ => Err(DecodeError::NotModule),
    }
}

/// The payload of `record` into `out`; its length.
pub fn encode(record: &ModuleRecord, out: &mut [u8]) -> Option<usize> {
    let (head, body) = out.split_at_mut_checked(2)?;
    head.copy_from_slice(&[MARKER, VERSION]);
    let used = postcard::to_slice(record, body).ok()?.len();
    Some(2 + used)
}

fn xor<const N: usize>(a: &[u8; N], b: &[u8]) -> [u8; N] {
    core::array::from_fn(|i| a.get(i).copied().unwrap_or(0) ^ b.get(i).copied().unwrap_or(0))
}

/// The pad and tag key of `counter` in a session: the pad seals the derivation, the tag
/// covers counter and sealed bytes.
fn phrase_pad(isk: &SessionKey, counter: u32) -> [u8; 64] {
    let mut label = [0u8; LABEL_PHRASE_PAD.len() + 4];
    let (l, c) = label.split_at_mut(LABEL_PHRASE_PAD.len());
    l.copy_from_slice(LABEL_PHRASE_PAD);
    c.copy_from_slice(&counter.to_le_bytes());
    isk.derive(&label)
}

fn phrase_tag(isk: &SessionKey, counter: u32, sealed: &[u8; PRS_BYTES]) -> [u8; TAG_BYTES] {
    let mut label = [0u8; LABEL_PHRASE_TAG.len() + 4 + PRS_BYTES];
    let (l, rest) = label.split_at_mut(LABEL_PHRASE_TAG.len());
    let (c, s) = rest.split_at_mut(4);
    l.copy_from_slice(LABEL_PHRASE_TAG);
    c.copy_from_slice(&counter.to_le_bytes());
    s.copy_from_slice(sealed);
    isk.derive16(&label)
}

/// The module's side of one exchange, between its challenge and the phone's response.
#[derive(Debug)]
pub struct ModuleExchange {
    exchange: Exchange,
    challenge: Challenge,
}

/// A confirmed phone session at the module.
#[derive(Debug, Clone, Copy)]
pub struct ModuleSession {
    isk: SessionKey,
    highest: u32,
}

impl ModuleExchange {
    /// A challenge on `secret` (the module's stored phrase derivation), session and scalar
    /// from `random` (32 bytes of a hardware RNG, fresh per exchange).
    pub fn new(secret: &PhraseSecret, random: &[u8; 32]) -> Self {
        let session: [u8; 8] = core::array::from_fn(|i| random.get(i).copied().unwrap_or(0));
        let exchange = Exchange::start(&secret.prs, PHONE_CI, &session, random);
        let challenge = Challenge {
            salt: secret.salt,
            session,
            share: exchange.share(),
        };
        Self {
            exchange,
            challenge,
        }
    }

    /// The challenge to send.
    pub fn challenge(&self) -> Challenge {
        self.challenge
    }

    /// The phone's response: on a right confirmation the session and what to send
    /// (`Granted`, carrying `change_key` sealed); `None` on a wrong one.
    pub fn respond(
        &self,
        response: &Response,
        change_key: Option<&ChangeKey>,
    ) -> Option<(ModuleSession, Granted)> {
        let isk = self.exchange.finish(
            Role::Initiator,
            &response.share,
            &self.challenge.salt,
            &[],
            &self.challenge.session,
        )?;
        if !tags_equal(&isk.derive16(LABEL_PHONE_TAG), &response.tag) {
            return None;
        }
        let granted = Granted {
            tag: isk.derive16(LABEL_MODULE_TAG),
            change_key: change_key.map(|k| xor(k.as_bytes(), &isk.derive16(LABEL_CHANGE_KEY))),
        };
        Some((ModuleSession { isk, highest: 0 }, granted))
    }
}

impl ModuleSession {
    /// A new phrase from the phone: its derivation (under the module's salt) if the tag
    /// verifies and the counter is fresh (then used up); the refusal otherwise.
    pub fn open(&mut self, record: &SetPhrase) -> Result<[u8; PRS_BYTES], Refusal> {
        if !tags_equal(
            &phrase_tag(&self.isk, record.counter, &record.sealed),
            &record.tag,
        ) {
            return Err(Refusal::NotAuthenticated);
        }
        if record.counter <= self.highest {
            return Err(Refusal::Replayed);
        }
        self.highest = record.counter;
        Ok(xor(&record.sealed, &phrase_pad(&self.isk, record.counter)))
    }

    /// The highest counter taken in this session.
    pub fn highest(&self) -> u32 {
        self.highest
    }
}

/// The phone's side: derives the phrase under the module's salt, answers the challenge,
/// learns the change key, and seals new phrases (the ground station runs it in WASM; the
/// simulators' phones too).
#[derive(Debug)]
pub struct PhoneSession {
    phrase_salted: Option<(Challenge, SessionKey)>,
    counter: u32,
}

impl PhoneSession {
    /// The phone's response to `challenge` for `phrase` (already checked,
    /// [`crate::link::check_phrase`]), its scalar from `random`; the session waiting for
    /// the module's grant. `None` when the module's share is invalid.
    pub fn respond(
        phrase: &str,
        challenge: &Challenge,
        random: &[u8; 32],
    ) -> Option<(Self, Response)> {
        let secret = PhraseSecret::derive(phrase, challenge.salt);
        Self::respond_with(&secret, challenge, random)
    }

    /// [`PhoneSession::respond`] with the phrase's derivation already made.
    pub fn respond_with(
        secret: &PhraseSecret,
        challenge: &Challenge,
        random: &[u8; 32],
    ) -> Option<(Self, Response)> {
        let exchange = Exchange::start(&secret.prs, PHONE_CI, &challenge.session, random);
        let isk = exchange.finish(
            Role::Responder,
            &challenge.share,
            &[],
            &challenge.salt,
            &challenge.session,
        )?;
        let response = Response {
            share: exchange.share(),
            tag: isk.derive16(LABEL_PHONE_TAG),
        };
        let session = Self {
            phrase_salted: Some((*challenge, isk)),
            counter: 0,
        };
        Some((session, response))
    }

    /// The module's grant, if its confirmation verifies (the module knows the phrase): the
    /// change key it carries (`None` while the module has no keyed link). A wrong one is
    /// [`Refusal::NotAuthenticated`].
    pub fn on_granted(&self, granted: &Granted) -> Result<Option<ChangeKey>, Refusal> {
        let (_, isk) = self
            .phrase_salted
            .as_ref()
            .ok_or(Refusal::NotAuthenticated)?;
        if !tags_equal(&isk.derive16(LABEL_MODULE_TAG), &granted.tag) {
            return Err(Refusal::NotAuthenticated);
        }
        Ok(granted
            .change_key
            .map(|k| ChangeKey::from_bytes(xor(&k, &isk.derive16(LABEL_CHANGE_KEY)))))
    }

    /// A new phrase (already checked) for the module, sealed with the next counter.
    pub fn set_phrase(&mut self, phrase: &str) -> Option<SetPhrase> {
        let (challenge, _) = self.phrase_salted.as_ref()?;
        let secret = PhraseSecret::derive(phrase, challenge.salt);
        self.set_phrase_with(&secret)
    }

    /// [`PhoneSession::set_phrase`] with the new phrase's derivation already made (under
    /// the module's salt: the challenge's).
    pub fn set_phrase_with(&mut self, secret: &PhraseSecret) -> Option<SetPhrase> {
        let (_, isk) = self.phrase_salted.as_ref()?;
        self.counter = self.counter.wrapping_add(1);
        let sealed = xor(&secret.prs, &phrase_pad(isk, self.counter));
        Some(SetPhrase {
            counter: self.counter,
            sealed,
            tag: phrase_tag(isk, self.counter, &sealed),
        })
    }

    /// The module's answer: adopt its counter, so the next record is fresh.
    pub fn on_answer(&mut self, answer: &Answer) {
        self.counter = self.counter.max(answer.counter);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::LinkKey;
    use crate::messages::Message;

    fn secret(phrase: &str) -> PhraseSecret {
        PhraseSecret::derive(phrase, [7; 8])
    }

    fn change_key() -> ChangeKey {
        ChangeKey::from_link_key(&LinkKey::from_bytes([0x33; 16]))
    }

    #[test]
    fn the_phone_with_the_phrase_gets_the_change_key_sealed() {
        let module = ModuleExchange::new(&secret("amber kettle under the oak"), &[1; 32]);
        let challenge = module.challenge();
        let (phone, response) =
            PhoneSession::respond("amber kettle under the oak", &challenge, &[2; 32]).unwrap();
        let (_, granted) = module
            .respond(&response, Some(&change_key()))
            .expect("confirmed");
        assert_ne!(
            granted.change_key.as_ref(),
            Some(change_key().as_bytes()),
            "never in clear"
        );
        assert_eq!(phone.on_granted(&granted), Ok(Some(change_key())));
        // Another phrase: the module refuses; a module that does not know the phrase is
        // not believed by the phone either.
        let (_, wrong) =
            PhoneSession::respond("amber kettle under the elm", &challenge, &[2; 32]).unwrap();
        assert!(module.respond(&wrong, Some(&change_key())).is_none());
        let forged = Granted {
            tag: [0x42; 16],
            ..granted
        };
        assert_eq!(phone.on_granted(&forged), Err(Refusal::NotAuthenticated));
    }

    #[test]
    fn a_set_phrase_opens_once_in_its_session_with_a_fresh_pad_each_session() {
        let stored = secret("amber kettle under the oak");
        let mut pads = Vec::new();
        for round in 0..2u8 {
            let module = ModuleExchange::new(&stored, &[10 + round; 32]);
            let (mut phone, response) = PhoneSession::respond(
                "amber kettle under the oak",
                &module.challenge(),
                &[20 + round; 32],
            )
            .unwrap();
            let (mut session, _) = module.respond(&response, None).unwrap();
            let record = phone.set_phrase("brass lantern at the weir").unwrap();
            assert_eq!(
                record.counter, 1,
                "a fresh phone signs counter 1 every time"
            );
            assert_eq!(
                session.open(&record),
                Ok(secret("brass lantern at the weir").prs)
            );
            assert_eq!(session.open(&record), Err(Refusal::Replayed));
            let mut forged = record;
            forged.sealed[0] ^= 1;
            assert_eq!(session.open(&forged), Err(Refusal::NotAuthenticated));
            // The pad is the sealed bytes XOR the derivation.
            pads.push(xor(
                &record.sealed,
                &secret("brass lantern at the weir").prs,
            ));
        }
        assert_ne!(pads[0], pads[1], "two sessions never share a pad");
    }

    #[test]
    fn records_round_trip_and_are_never_messages() {
        let records = [
            ModuleRecord::Hello,
            ModuleRecord::Challenge(ModuleExchange::new(&secret("x"), &[3; 32]).challenge()),
            ModuleRecord::Response(Response {
                share: [4; 32],
                tag: [5; 16],
            }),
            ModuleRecord::Granted(Granted {
                tag: [6; 16],
                change_key: Some([7; 16]),
            }),
            ModuleRecord::SetPhrase(SetPhrase {
                counter: u32::MAX,
                sealed: [8; 32],
                tag: [9; 16],
            }),
            ModuleRecord::Answer(Answer {
                outcome: Outcome::Refused(Refusal::Locked),
                counter: u32::MAX,
            }),
            ModuleRecord::LinkSecurity(LinkSecurity {
                tag_failures_down: u32::MAX,
                tag_failures_up: 1,
                alert: true,
            }),
        ];
        for record in records {
            let mut out = [0u8; MAX_PAYLOAD_BYTES];
            let n = encode(&record, &mut out).unwrap();
            assert!(is_module_payload(&out[..n]));
            assert_eq!(decode(&out[..n]), Ok(record));
            assert!(postcard::from_bytes::<Message>(&out[..n]).is_err());
            let mut other = out;
            other[1] = VERSION + 1;
            assert_eq!(decode(&other[..n]), Err(DecodeError::Version(VERSION + 1)));
        }
        // Version 1 records (a key proposed in the clear among them) are not read.
        let mut proposal = vec![MARKER, 1, 0];
        proposal.extend([0x5A; 16]);
        assert_eq!(decode(&proposal), Err(DecodeError::Version(1)));
        assert_eq!(decode(&[0x00, 1, 2]), Err(DecodeError::NotModule));
        assert_eq!(decode(&[MARKER]), Err(DecodeError::Malformed));
        assert_eq!(decode(&[MARKER, VERSION, 99]), Err(DecodeError::Malformed));
    }
}
