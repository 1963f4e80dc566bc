//! Authenticated setting changes from the phone (spec §12.5): who may change the flight
//! side's settings over the module's HM-10 relay. Read-only telemetry needs no secret; a
//! change does, and it is checked end to end on the flight side (the module relays the
//! record unread).
//!
//! * **Key:** 128 bits derived one-way from the link key, `SipHash-2-4(link key,
//!   "TauLink/1 phone/0") ‖ SipHash-2-4(link key, "TauLink/1 phone/1")`, so a phone MAC is
//!   never an air tag, and the link key itself never leaves the two ends. The phone gets the
//!   change key from the module, sealed under the session key of a CPace exchange on the
//!   binding phrase (`crate::module_record`): nothing on BLE tests a phrase offline.
//! * **Tag:** the full 64 bits of SipHash-2-4(change key, "TauLink/1 change" ‖ session ‖
//!   counter ‖ id ‖ value), all little-endian: forgery 2⁻⁶⁴ per try.
//! * **Replay:** the flight side draws a random 32-bit session at boot and accepts a counter
//!   only above the highest it accepted in that session. A recorded change fails in the same
//!   session (its counter is used) and in any later one (another session is in its tag).
//!   Every refusal tells the phone the session and the highest counter
//!   ([`crate::messages::ChangeRefused`]), so a phone that lost track signs the next change
//!   afresh.

use crate::link::LinkKey;
use crate::link::auth::{KEY_BYTES, sip};
use crate::messages::{ChangeRefused, RefuseReason, SettingChange, SignedChange};

const DOMAIN_KEY_LOW: &[u8] = b"TauLink/1 phone/0";
const DOMAIN_KEY_HIGH: &[u8] = b"TauLink/1 phone/1";
const DOMAIN_CHANGE: &[u8] = b"TauLink/1 change";

/// The key of the phone's setting changes. `Debug` does not print it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct ChangeKey([u8; KEY_BYTES]);

impl core::fmt::Debug for ChangeKey {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("ChangeKey(..)")
    }
}

impl ChangeKey {
    /// The change key of a link key.
    pub fn from_link_key(key: &LinkKey) -> Self {
        let mut bytes = [0u8; KEY_BYTES];
        let (low, high) = bytes.split_at_mut(8);
        low.copy_from_slice(&key.prf(DOMAIN_KEY_LOW).to_le_bytes());
        high.copy_from_slice(&key.prf(DOMAIN_KEY_HIGH).to_le_bytes());
        Self(bytes)
    }

    /// The key's bytes (to seal it for the phone, `crate::module_record`).
    pub(crate) fn as_bytes(&self) -> &[u8; KEY_BYTES] {
        &self.0
    }

    /// The key from its bytes (unsealed by the phone, `crate::module_record`).
    pub(crate) const fn from_bytes(bytes: [u8; KEY_BYTES]) -> Self {
        Self(bytes)
    }

    /// The tag of `change` signed with `counter` in the flight side's `session`.
    pub fn tag(&self, session: u32, counter: u32, change: &SettingChange) -> [u8; 8] {
        let (s, c) = (session.to_le_bytes(), counter.to_le_bytes());
        let (id, value) = (change.id.to_le_bytes(), change.value.to_le_bytes());
        sip(&self.0, &[DOMAIN_CHANGE, &s, &c, &id, &value]).to_le_bytes()
    }

    /// `change` signed with `counter` in `session`: what the phone sends.
    pub fn sign(&self, session: u32, counter: u32, change: SettingChange) -> SignedChange {
        SignedChange {
            change,
            counter,
            tag: self.tag(session, counter, &change),
        }
    }

    /// Whether `signed` carries the right tag for `session` (in time independent of where a
    /// wrong tag differs). The counter's freshness is the caller's check.
    pub fn verify(&self, session: u32, signed: &SignedChange) -> bool {
        let want = self.tag(session, signed.counter, &signed.change);
        want.iter()
            .zip(signed.tag.iter())
            .fold(0u8, |acc, (a, b)| acc | (a ^ b))
            == 0
    }
}

/// The phone's side (the ground station runs it in WASM; the simulators' phones too): signs
/// changes with a counter that only grows, and learns the flight side's session from its
/// refusals.
#[derive(Debug, Clone)]
pub struct Signer {
    key: ChangeKey,
    session: u32,
    counter: u32,
}

impl Signer {
    /// A phone that knows the change key (from the module, `crate::module_record`) but no
    /// session yet: its first change is refused with the session, and
    /// [`Signer::on_refused`] says to send it again.
    pub fn new(key: ChangeKey) -> Self {
        Self {
            key,
            session: 0,
            counter: 0,
        }
    }

    /// `change`, signed with the next counter.
    pub fn sign(&mut self, change: SettingChange) -> SignedChange {
        self.counter = self.counter.wrapping_add(1);
        self.key.sign(self.session, self.counter, change)
    }

    /// The flight side refused a change: adopt its session and counter. Returns whether
    /// signing the change again can succeed (it failed only for a session or counter this
    /// phone did not know), so a wrong phrase is not retried forever.
    pub fn on_refused(&mut self, refused: &ChangeRefused) -> bool {
        let stale = refused.session != self.session || refused.counter >= self.counter;
        if refused.session != self.session {
            self.session = refused.session;
            self.counter = refused.counter;
        } else {
            self.counter = self.counter.max(refused.counter);
        }
        stale
            && matches!(
                refused.reason,
                RefuseReason::NotAuthenticated | RefuseReason::Replayed
            )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key() -> ChangeKey {
        ChangeKey::from_link_key(&LinkKey::from_bytes([0x11; 16]))
    }

    #[test]
    fn a_tag_binds_session_counter_id_and_value() {
        let change = SettingChange { id: 7, value: -3 };
        let signed = key().sign(0xC0FFEE, 5, change);
        assert!(key().verify(0xC0FFEE, &signed));
        assert!(!key().verify(0xC0FFEF, &signed), "another session");
        let mut other = signed;
        other.counter = 6;
        assert!(!key().verify(0xC0FFEE, &other), "another counter");
        other = signed;
        other.change.value = -4;
        assert!(!key().verify(0xC0FFEE, &other), "another value");
        other = signed;
        other.change.id = 8;
        assert!(!key().verify(0xC0FFEE, &other), "another setting");
        let wrong = ChangeKey::from_link_key(&LinkKey::from_bytes([0x22; 16]));
        assert!(!wrong.verify(0xC0FFEE, &signed), "another phrase");
        for bit in 0..64 {
            let mut forged = signed;
            forged.tag[bit / 8] ^= 1 << (bit % 8);
            assert!(!key().verify(0xC0FFEE, &forged), "bit {bit}");
        }
    }

    #[test]
    fn a_signer_learns_the_session_from_one_refusal_and_a_wrong_phrase_stops() {
        let link = LinkKey::from_bytes([0x11; 16]);
        let mut phone = Signer::new(ChangeKey::from_link_key(&link));
        let change = SettingChange { id: 1, value: 2 };
        let first = phone.sign(change);
        assert!(!key().verify(77, &first), "no session known yet");
        let refused = ChangeRefused {
            id: 1,
            reason: RefuseReason::NotAuthenticated,
            session: 77,
            counter: 9,
        };
        assert!(phone.on_refused(&refused), "worth one more try");
        let second = phone.sign(change);
        assert!(key().verify(77, &second));
        assert_eq!(second.counter, 10);
        // The same refusal again (the tag was right for 77/10, so this means another
        // phrase): no retry.
        let again = ChangeRefused {
            counter: 9,
            ..refused
        };
        assert!(!phone.on_refused(&again));
        let armed = ChangeRefused {
            reason: RefuseReason::Armed,
            session: 78,
            ..refused
        };
        assert!(!phone.on_refused(&armed), "armed: nothing to retry");
    }

    #[test]
    fn the_change_key_is_neither_the_link_key_nor_printed() {
        let link = LinkKey::from_bytes([0x11; 16]);
        assert_ne!(key().0, link.to_bytes());
        assert_eq!(format!("{:?}", key()), "ChangeKey(..)");
    }
}
