//! Records for the TauLink module itself on the HM-10 relay (spec §12.5): the phone proposes
//! the module's link key (from a binding phrase typed on the phone), the module answers. Every
//! other phone record goes on to the flight side unread; these stop at the module.
//!
//! **Wire format.** Framed like every relay record (`COBS(payload ‖ crc16_be) ‖ 0x00`,
//! [`crate::framing`]); the payload is [`MARKER`], [`VERSION`], then the postcard encoding of a
//! [`ModuleRecord`]. A telemetry [`crate::messages::Message`] starts with its postcard variant
//! number, a one-byte varint below 0x80 for any message set of fewer than 128 variants, so no
//! message starts with 0xA5: the module tells the two apart by the first byte, and a flight
//! side that ever saw a module record would drop it as unknown. A record of another version is
//! refused by [`decode`] (the phone then learns nothing from the module and says so).
//!
//! **Two ways to change the key.**
//! * [`ModuleRecord::ProposeKey`]: the new key in the clear (the BLE link is protected by the
//!   HM-10's PIN and bonding only). The module applies it only after the pilot confirms on the
//!   handset — a CRSF command showing the proposed key's fingerprint — so a phone that knows
//!   nothing can change nothing by itself.
//! * [`ModuleRecord::SignedKey`]: for a phone that knows the module's current phrase. It
//!   derives the change key from the current link key exactly as for flight-side setting
//!   changes ([`crate::change_auth::ChangeKey`]), seals the new key with a one-time pad from it,
//!   `pad = SipHash-2-4(ck, "TauLink/1 key-wrap" ‖ session ‖ counter ‖ 0) ‖ (… ‖ 1)`, and tags
//!   the sealed bytes, `tag = SipHash-2-4(ck, "TauLink/1 key-change" ‖ session ‖ counter ‖
//!   sealed)` (64 bits: forgery 2⁻⁶⁴ per try; the domains differ from every other use of the
//!   change key, so no flight-side change tag is ever a key-change tag). The module applies it
//!   at once if the tag verifies under its **session** (random per boot) and the counter is
//!   above every one it accepted in that session, so a recorded record fails in its own
//!   session and in every later boot. The new key never crosses BLE in the clear.
//!
//! Never while the quad is armed; every outcome is answered with a
//! [`ModuleRecord::KeyAnswer`] that carries the module's session and highest counter, so a
//! phone that did not know them signs again once ([`KeySigner::on_answer`]).

use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

use crate::change_auth::ChangeKey;
use crate::link::LinkKey;
use crate::link::auth::{KEY_BYTES, sip_cold};

/// First payload byte of every module record (never the first byte of a message).
pub const MARKER: u8 = 0xA5;
/// The record format's version (the second payload byte).
pub const VERSION: u8 = 1;
/// Largest payload of a module record.
pub const MAX_PAYLOAD_BYTES: usize = 2 + ModuleRecord::POSTCARD_MAX_SIZE;

const DOMAIN_WRAP: &[u8] = b"TauLink/1 key-wrap";
const DOMAIN_TAG: &[u8] = b"TauLink/1 key-change";

/// A new link key, sealed and signed under the module's current one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SignedKey {
    /// The new key XOR the pad of (session, counter).
    pub sealed: [u8; KEY_BYTES],
    /// Above every counter the module accepted in its session.
    pub counter: u32,
    /// SipHash-2-4 tag over session, counter and `sealed`.
    pub tag: [u8; 8],
}

/// Why the module did not take a key from the phone.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum KeyRefusal {
    /// The quad is armed (as far as the module heard): no key change in flight.
    Armed,
    /// The tag does not verify (another phrase, a forgery).
    NotAuthenticated,
    /// The counter is not above the highest accepted (a replay, or a stale session).
    Replayed,
    /// A signed key, but the module has no phrase to check it with: propose instead.
    NoPhrase,
    /// The pilot cancelled the confirmation on the handset.
    Declined,
    /// Nobody confirmed on the handset in time (or a newer proposal replaced this one).
    Expired,
}

/// What became of a key from the phone.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum KeyOutcome {
    /// The key is in force (the module's link restarted with it, and it is saved).
    Applied,
    /// Waiting for the pilot to confirm on the handset ("Phone Phrase" command).
    AwaitingConfirmation,
    /// Not taken.
    Refused(KeyRefusal),
}

/// The module's answer to a key from the phone.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KeyAnswer {
    /// What happened.
    pub outcome: KeyOutcome,
    /// The fingerprint ([`LinkKey::fingerprint`]) of the key the answer is about: the one in
    /// force after `Applied` or a refusal (`None`: no phrase), the proposed one while waiting.
    pub fingerprint: Option<u32>,
    /// The module's session nonce for this boot (to sign with).
    pub session: u32,
    /// The highest counter the module accepted in the session (sign with a greater one).
    pub counter: u32,
}

/// Everything module-addressed on the relay.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, MaxSize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModuleRecord {
    /// Phone → module: use this key once the pilot confirms on the handset.
    ProposeKey([u8; KEY_BYTES]),
    /// Phone → module: use this key, signed under the current one (applied at once).
    SignedKey(SignedKey),
    /// Module → phone: the outcome.
    KeyAnswer(KeyAnswer),
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

fn pad(key: &ChangeKey, session: u32, counter: u32) -> [u8; KEY_BYTES] {
    let mut pad = [0u8; KEY_BYTES];
    for (half, index) in pad.chunks_exact_mut(8).zip(0u8..) {
        let (s, c) = (session.to_le_bytes(), counter.to_le_bytes());
        let h = sip_cold(key.as_bytes(), &[DOMAIN_WRAP, &s, &c, &[index]]);
        half.copy_from_slice(&h.to_le_bytes());
    }
    pad
}

fn tag(key: &ChangeKey, session: u32, counter: u32, sealed: &[u8; KEY_BYTES]) -> [u8; 8] {
    let (s, c) = (session.to_le_bytes(), counter.to_le_bytes());
    sip_cold(key.as_bytes(), &[DOMAIN_TAG, &s, &c, sealed]).to_le_bytes()
}

fn xor(a: &[u8; KEY_BYTES], b: &[u8; KEY_BYTES]) -> [u8; KEY_BYTES] {
    let mut out = [0u8; KEY_BYTES];
    for ((o, x), y) in out.iter_mut().zip(a).zip(b) {
        *o = x ^ y;
    }
    out
}

/// `new` sealed and signed under `current` for the module's `session` with `counter`.
pub fn seal(current: &LinkKey, session: u32, counter: u32, new: &LinkKey) -> SignedKey {
    let key = ChangeKey::from_link_key(current);
    let sealed = xor(&new.to_bytes(), &pad(&key, session, counter));
    SignedKey {
        sealed,
        counter,
        tag: tag(&key, session, counter, &sealed),
    }
}

/// The new key in `signed` if its tag verifies under `current` and `session` (in time
/// independent of where a wrong tag differs); the counter's freshness is the caller's check.
pub fn open(current: &LinkKey, session: u32, signed: &SignedKey) -> Option<LinkKey> {
    let key = ChangeKey::from_link_key(current);
    let want = tag(&key, session, signed.counter, &signed.sealed);
    let diff = want
        .iter()
        .zip(signed.tag.iter())
        .fold(0u8, |acc, (a, b)| acc | (a ^ b));
    (diff == 0)
        .then(|| LinkKey::from_bytes(xor(&signed.sealed, &pad(&key, session, signed.counter))))
}

/// The phone's side: seals new keys under the module's current one with a counter that only
/// grows, and learns the module's session from its answers.
#[derive(Debug, Clone)]
pub struct KeySigner {
    current: LinkKey,
    session: u32,
    counter: u32,
}

impl KeySigner {
    /// A phone that knows the module's current key but not its session yet: the first
    /// record is refused with the session, and [`KeySigner::on_answer`] says to send again.
    pub fn new(current: &LinkKey) -> Self {
        Self {
            current: *current,
            session: 0,
            counter: 0,
        }
    }

    /// `new`, sealed with the next counter.
    pub fn seal(&mut self, new: &LinkKey) -> SignedKey {
        self.counter = self.counter.wrapping_add(1);
        seal(&self.current, self.session, self.counter, new)
    }

    /// The module answered: adopt its session and counter. Returns whether sealing the key
    /// again can succeed (it was refused only for a session or counter this phone did not
    /// know), so a wrong phrase is not retried forever.
    pub fn on_answer(&mut self, answer: &KeyAnswer) -> bool {
        let stale = answer.session != self.session || answer.counter >= self.counter;
        if answer.session != self.session {
            self.session = answer.session;
            self.counter = answer.counter;
        } else {
            self.counter = self.counter.max(answer.counter);
        }
        stale
            && matches!(
                answer.outcome,
                KeyOutcome::Refused(KeyRefusal::NotAuthenticated | KeyRefusal::Replayed)
            )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{Message, SettingChange};

    fn old() -> LinkKey {
        LinkKey::from_phrase("correct horse battery staple")
    }
    fn new() -> LinkKey {
        LinkKey::from_phrase("tr0ub4dor and 3")
    }

    #[test]
    fn a_sealed_key_opens_only_under_its_key_session_and_bytes() {
        let signed = seal(&old(), 77, 5, &new());
        assert_eq!(open(&old(), 77, &signed), Some(new()));
        assert_ne!(signed.sealed, new().to_bytes(), "never in the clear");
        assert_eq!(open(&old(), 78, &signed), None, "another session");
        assert_eq!(open(&new(), 77, &signed), None, "another phrase");
        let mut other = signed;
        other.counter = 6;
        assert_eq!(open(&old(), 77, &other), None, "another counter");
        for bit in 0..128 {
            let mut forged = signed;
            forged.sealed[bit / 8] ^= 1 << (bit % 8);
            assert_eq!(open(&old(), 77, &forged), None, "sealed bit {bit}");
        }
        for bit in 0..64 {
            let mut forged = signed;
            forged.tag[bit / 8] ^= 1 << (bit % 8);
            assert_eq!(open(&old(), 77, &forged), None, "tag bit {bit}");
        }
        // A flight-side change tag of the same key is no key-change tag.
        let change =
            ChangeKey::from_link_key(&old()).sign(77, 5, SettingChange { id: 0, value: 0 });
        let crossed = SignedKey {
            tag: change.tag,
            ..signed
        };
        assert_eq!(open(&old(), 77, &crossed), None);
    }

    #[test]
    fn records_round_trip_and_are_never_messages() {
        let records = [
            ModuleRecord::ProposeKey(new().to_bytes()),
            ModuleRecord::SignedKey(seal(&old(), 1, 2, &new())),
            ModuleRecord::KeyAnswer(KeyAnswer {
                outcome: KeyOutcome::Refused(KeyRefusal::Expired),
                fingerprint: Some(u32::MAX),
                session: u32::MAX,
                counter: u32::MAX,
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
        assert_eq!(decode(&[0x00, 1, 2]), Err(DecodeError::NotModule));
        assert_eq!(decode(&[MARKER]), Err(DecodeError::Malformed));
        assert_eq!(decode(&[MARKER, VERSION, 9]), Err(DecodeError::Malformed));
    }

    #[test]
    fn a_signer_learns_the_session_from_one_answer_and_a_wrong_phrase_stops() {
        let mut phone = KeySigner::new(&old());
        let first = phone.seal(&new());
        assert_eq!(open(&old(), 77, &first), None, "no session known yet");
        let refused = KeyAnswer {
            outcome: KeyOutcome::Refused(KeyRefusal::NotAuthenticated),
            fingerprint: None,
            session: 77,
            counter: 9,
        };
        assert!(phone.on_answer(&refused), "worth one more try");
        let second = phone.seal(&new());
        assert_eq!(second.counter, 10);
        assert_eq!(open(&old(), 77, &second), Some(new()));
        assert!(
            !phone.on_answer(&refused),
            "the same refusal again: another phrase"
        );
        let armed = KeyAnswer {
            outcome: KeyOutcome::Refused(KeyRefusal::Armed),
            session: 78,
            ..refused
        };
        assert!(!phone.on_answer(&armed), "armed: nothing to retry");
    }
}
