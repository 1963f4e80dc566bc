//! CPace, the balanced password-authenticated key exchange of draft-irtf-cfrg-cpace, suite
//! CPACE-RISTR255-SHA512 (spec §12.1): two parties that share a password-related string
//! (PRS) — here the binding phrase's slow derivation, or nothing — each send one 32-byte
//! share and both derive the same 64-byte intermediate session key (ISK). A recording of
//! the exchange gives a guesser nothing to test a phrase against; an active party that does
//! not know the phrase learns whether one guess was right, per exchange.
//!
//! Suite choice: the ristretto255 one, not X25519 with Elligator 2, because curve25519-dalek
//! (the audited no_std implementation both firmwares link) exposes ristretto255's one-way
//! map (`RistrettoPoint::from_uniform_bytes`) but not the field arithmetic Elligator 2 on
//! the Montgomery curve needs, and cryptographic code is not ours to write. The same group,
//! prime order (no cofactor to clear), one implementation for the bind and the phone.
//!
//! Checked against the draft's test vectors (`G_Coffee25519` in the CFRG repository's
//! `testvectors.json`): generator, shares, K and ISK.

use curve25519_dalek::ristretto::{CompressedRistretto, RistrettoPoint};
use curve25519_dalek::scalar::Scalar;
use curve25519_dalek::traits::Identity;
use hmac::Mac;

use super::sha512::{HmacSha512, Sha512, hmac, sha512};

/// Bytes of an encoded share (a ristretto255 element).
pub const SHARE_BYTES: usize = 32;
/// Bytes of the intermediate session key (a SHA-512 output).
pub const ISK_BYTES: usize = 64;

/// The suite's domain separation identifier.
const DSI: &[u8] = b"CPaceRistretto255";
/// The ISK's domain separation identifier (`DSI ‖ "_ISK"`).
const DSI_ISK: &[u8] = b"CPaceRistretto255_ISK";
/// SHA-512's input block: the generator string pads DSI and PRS to fill it.
const HASH_BLOCK_BYTES: usize = 128;

/// The intermediate session key both parties derive. `Debug` does not print it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct SessionKey([u8; ISK_BYTES]);

impl core::fmt::Debug for SessionKey {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("SessionKey(..)")
    }
}

impl SessionKey {
    /// A key for `label`, one-way from the ISK: HMAC-SHA-512(ISK, label). Each use of the
    /// exchange (the link key, each confirmation tag) takes its own label.
    pub fn derive(&self, label: &[u8]) -> [u8; 64] {
        // HMAC takes keys of any length: this cannot fail.
        let Ok(mac) = HmacSha512::new_from_slice(&self.0) else {
            return [0; 64];
        };
        hmac(&mac, &[label])
    }

    /// The first 16 bytes of [`SessionKey::derive`]: a 128-bit key or confirmation tag.
    pub fn derive16(&self, label: &[u8]) -> [u8; 16] {
        let wide = self.derive(label);
        let mut out = [0u8; 16];
        out.copy_from_slice(wide.get(..16).unwrap_or(&[0; 16]));
        out
    }
}

/// Which share is the initiator's: the transcript orders them (initiator–responder mode).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Sent its share first (`Ya`).
    Initiator,
    /// Answered (`Yb`).
    Responder,
}

/// One party's side of an exchange: its secret scalar and its share.
pub struct Exchange {
    scalar: Scalar,
    share: [u8; SHARE_BYTES],
}

impl core::fmt::Debug for Exchange {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("Exchange(..)")
    }
}

impl Exchange {
    /// Starts an exchange for `prs` in channel `ci` and session `sid`, the secret scalar from
    /// `random` (32 bytes of a hardware RNG, hashed to a uniform scalar).
    pub fn start(prs: &[u8], ci: &[u8], sid: &[u8], random: &[u8; 32]) -> Self {
        let wide = sha512(&[b"TauLink/2 scalar", random]);
        Self::with_scalar(prs, ci, sid, Scalar::from_bytes_mod_order_wide(&wide))
    }

    fn with_scalar(prs: &[u8], ci: &[u8], sid: &[u8], scalar: Scalar) -> Self {
        let share = (generator(prs, ci, sid) * scalar).compress().to_bytes();
        Self { scalar, share }
    }

    /// This party's share, to send.
    pub fn share(&self) -> [u8; SHARE_BYTES] {
        self.share
    }

    /// The ISK from the `peer`'s share, with `ad_own` and `ad_peer` the associated data each
    /// side's share went with, in session `sid`; `None` if the peer's share is no valid
    /// element or gives the identity (a party that sent it knows nothing of the phrase).
    pub fn finish(
        &self,
        role: Role,
        peer: &[u8; SHARE_BYTES],
        ad_own: &[u8],
        ad_peer: &[u8],
        sid: &[u8],
    ) -> Option<SessionKey> {
        let point = CompressedRistretto(*peer).decompress()?;
        let k = point * self.scalar;
        if k == RistrettoPoint::identity() {
            return None;
        }
        let mut h = Sha512::new();
        lv(&mut h, DSI_ISK);
        lv(&mut h, sid);
        lv(&mut h, k.compress().as_bytes());
        let ((ya, ada), (yb, adb)) = match role {
            Role::Initiator => ((&self.share, ad_own), (peer, ad_peer)),
            Role::Responder => ((peer, ad_peer), (&self.share, ad_own)),
        };
        lv(&mut h, ya);
        lv(&mut h, ada);
        lv(&mut h, yb);
        lv(&mut h, adb);
        Some(SessionKey(h.finish()))
    }
}

/// Whether two tags are equal, in time independent of where they differ.
pub fn tags_equal(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// The generator of `prs` in channel `ci` and session `sid`: the one-way map of
/// SHA-512(lv_cat(DSI, PRS, zero padding to the hash block, CI, sid)).
fn generator(prs: &[u8], ci: &[u8], sid: &[u8]) -> RistrettoPoint {
    let prefixed = |len: usize| leb128_len(len) + len;
    let zpad = HASH_BLOCK_BYTES.saturating_sub(1 + prefixed(prs.len()) + prefixed(DSI.len()));
    let mut h = Sha512::new();
    lv(&mut h, DSI);
    lv(&mut h, prs);
    lv_zeros(&mut h, zpad);
    lv(&mut h, ci);
    lv(&mut h, sid);
    RistrettoPoint::from_uniform_bytes(&h.finish())
}

/// Bytes of the LEB128 encoding of `len`.
fn leb128_len(len: usize) -> usize {
    let mut n = 1;
    let mut rest = len >> 7;
    while rest != 0 {
        n += 1;
        rest >>= 7;
    }
    n
}

/// Hashes the LEB128 encoding of `len` (the draft's `prepend_len`).
fn length(h: &mut Sha512, len: usize) {
    let mut rest = len;
    loop {
        let byte = (rest & 0x7F) as u8;
        rest >>= 7;
        if rest == 0 {
            h.update(&[byte]);
            return;
        }
        h.update(&[byte | 0x80]);
    }
}

/// Hashes `data` with its length in front.
fn lv(h: &mut Sha512, data: &[u8]) {
    length(h, data.len());
    h.update(data);
}

/// Hashes `n` zero bytes with their length in front.
fn lv_zeros(h: &mut Sha512, n: usize) {
    length(h, n);
    for _ in 0..n {
        h.update(&[0]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b64(text: &str) -> Vec<u8> {
        const ABC: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut bits = 0u32;
        let mut n = 0;
        let mut out = Vec::new();
        for c in text.bytes().filter(|c| *c != b'=') {
            bits = bits << 6 | ABC.iter().position(|a| *a == c).unwrap() as u32;
            n += 6;
            if n >= 8 {
                n -= 8;
                out.push((bits >> n) as u8);
            }
        }
        out
    }

    fn arr<const N: usize>(text: &str) -> [u8; N] {
        b64(text).try_into().unwrap()
    }

    /// draft-irtf-cfrg-cpace's vectors for its ristretto255 suite (`G_Coffee25519`).
    #[test]
    fn matches_the_drafts_ristretto255_test_vectors() {
        let prs = b64("UGFzc3dvcmQ=");
        let ci = b64("b2MLQl9yZXNwb25kZXILQV9pbml0aWF0b3I=");
        let sid = b64("fktHkdao7wGbk2x5+38sVw==");
        assert_eq!(prs, b"Password");
        assert_eq!(
            generator(&prs, &ci, &sid).compress().to_bytes(),
            arr::<32>("pvyCw7iWj7suBv7oHKhYWG3qUNJI8MfKahiwkCows2s=")
        );
        let scalar = |text: &str| Scalar::from_canonical_bytes(arr(text)).unwrap();
        let a = Exchange::with_scalar(
            &prs,
            &ci,
            &sid,
            scalar("2j0jcAqeVpkliu+U3AYN/aXrth8Cpep3+tU/T/CXbQg="),
        );
        let b = Exchange::with_scalar(
            &prs,
            &ci,
            &sid,
            scalar("0jFrRUcYw1Ni2D1p32Mg84V47VmEZRQ14pSXYtkAuA0="),
        );
        assert_eq!(
            a.share(),
            arr::<32>("1A+yZaer6u55OdkaWF/ln3BT+YLCluxBPGJMZpMI+Ho=")
        );
        assert_eq!(
            b.share(),
            arr::<32>("CLz26Xd6nDE6PbbapRDy05hAMxnCNBvVBqkuZy634wc=")
        );
        let isk = arr::<64>(
            "TFRpoWsjZMS5ROvBp55R0WdK1H2ybocYFU9Z+uv6pS2DRvMKpYN3EX6yDVJ/LLxcdjgff9Ny6J34I5+H8uAu0Q==",
        );
        let from_a = a.finish(Role::Initiator, &b.share(), b"ADa", b"ADb", &sid);
        let from_b = b.finish(Role::Responder, &a.share(), b"ADb", b"ADa", &sid);
        assert_eq!(from_a, Some(SessionKey(isk)));
        assert_eq!(from_b, Some(SessionKey(isk)));
    }

    #[test]
    fn another_phrase_session_or_share_gives_another_key_and_invalid_shares_none() {
        let sid = [7u8; 12];
        let a = Exchange::start(b"phrase one", b"ci", &sid, &[1; 32]);
        let b = Exchange::start(b"phrase one", b"ci", &sid, &[2; 32]);
        let c = Exchange::start(b"phrase two", b"ci", &sid, &[2; 32]);
        let agreed = a.finish(Role::Initiator, &b.share(), b"", b"", &sid);
        assert!(agreed.is_some());
        assert_eq!(
            agreed,
            b.finish(Role::Responder, &a.share(), b"", b"", &sid)
        );
        assert_ne!(
            a.finish(Role::Initiator, &c.share(), b"", b"", &sid),
            c.finish(Role::Responder, &a.share(), b"", b"", &sid),
            "another phrase: the keys differ"
        );
        assert_ne!(
            agreed,
            a.finish(Role::Initiator, &b.share(), b"x", b"", &sid),
            "the associated data is in the transcript"
        );
        // The identity and a non-canonical encoding are refused.
        assert_eq!(a.finish(Role::Initiator, &[0; 32], b"", b"", &sid), None);
        assert_eq!(a.finish(Role::Initiator, &[0xFF; 32], b"", b"", &sid), None);
        assert_eq!(
            format!("{a:?} {:?}", agreed.unwrap()),
            "Exchange(..) SessionKey(..)"
        );
        let key = agreed.unwrap();
        assert_ne!(key.derive16(b"one"), key.derive16(b"two"));
        assert!(tags_equal(&key.derive16(b"one"), &key.derive16(b"one")));
        assert!(!tags_equal(&key.derive16(b"one"), &key.derive16(b"two")));
    }

    #[test]
    fn lengths_are_leb128() {
        assert_eq!(leb128_len(0), 1);
        assert_eq!(leb128_len(127), 1);
        assert_eq!(leb128_len(128), 2);
        assert_eq!(leb128_len(16_383), 2);
        assert_eq!(leb128_len(16_384), 3);
    }
}
