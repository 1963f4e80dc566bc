//! The link's SHA-512 (the CPace generator and transcript, its scalar, the bind's session
//! nonce, the entropy pool) and HMAC-SHA-512 (the phrase's PBKDF2, CPace's derived keys):
//! one out-of-line copy of the hasher's buffering and padding and one of HMAC's, instead
//! of one inlined at each call site (≈ 0.4 KB of flash each, issue 33). A call costs a
//! few instructions against the thousands of a compression.

use hmac::{Hmac, Mac};
use sha2::{Digest, Sha512 as Inner};

/// HMAC-SHA-512 under a key already set up (`Mac::new_from_slice`).
pub(crate) type HmacSha512 = Hmac<Inner>;

/// A SHA-512 fed in pieces.
pub(crate) struct Sha512(Inner);

impl Sha512 {
    /// An empty hash.
    pub(crate) fn new() -> Self {
        Self(Inner::new())
    }

    /// Feeds `data`.
    #[inline(never)]
    pub(crate) fn update(&mut self, data: &[u8]) {
        self.0.update(data);
    }

    /// The digest.
    #[inline(never)]
    pub(crate) fn finish(self) -> [u8; 64] {
        self.0.finalize().into()
    }
}

/// SHA-512 of `parts`, in order.
pub(crate) fn sha512(parts: &[&[u8]]) -> [u8; 64] {
    let mut h = Sha512::new();
    for part in parts {
        h.update(part);
    }
    h.finish()
}

/// HMAC-SHA-512 of `parts`, in order, under `mac`'s key (`mac` itself stays unfed, so a
/// PBKDF2 reuses it every iteration).
#[inline(never)]
pub(crate) fn hmac(mac: &HmacSha512, parts: &[&[u8]]) -> [u8; 64] {
    let mut mac = mac.clone();
    for part in parts {
        mac.update(part);
    }
    mac.finalize().into_bytes().into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_fips_180_2_vector_whole_and_in_pieces() {
        // FIPS 180-2, appendix C.1: SHA-512("abc").
        let expected_head = [0xdd, 0xaf, 0x35, 0xa1, 0x93, 0x61, 0x7a, 0xba];
        let whole = sha512(&[b"abc"]);
        assert_eq!(whole[..8], expected_head);
        assert_eq!(
            whole[56..],
            [0x2a, 0x9a, 0xc9, 0x4f, 0xa5, 0x4c, 0xa4, 0x9f]
        );
        assert_eq!(sha512(&[b"a", b"", b"bc"]), whole);
    }

    #[test]
    fn hmac_matches_rfc_4231_test_case_2_and_leaves_the_key_unfed() {
        // RFC 4231 §4.3: key "Jefe", data "what do ya want for nothing?".
        let mac = HmacSha512::new_from_slice(b"Jefe").unwrap();
        let tag = hmac(&mac, &[b"what do ya want ", b"for nothing?"]);
        assert_eq!(tag[..8], [0x16, 0x4b, 0x7a, 0x7b, 0xfc, 0xf8, 0x19, 0xe2]);
        assert_eq!(tag[56..], [0x63, 0x6e, 0x07, 0x0a, 0x38, 0xbc, 0xe7, 0x37]);
        assert_eq!(hmac(&mac, &[b"what do ya want for nothing?"]), tag);
    }
}
