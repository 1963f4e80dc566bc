//! The link's SHA-512 for everything but the phrase's PBKDF2 (the CPace generator and
//! transcript, its scalar, the bind's session nonce, the entropy pool): one out-of-line
//! copy of the hasher's buffering and padding, instead of one inlined at each of those
//! call sites (≈ 0.4 KB of flash each, issue 33). They run once per bind or draw, so the
//! calls cost nothing that matters.

use sha2::{Digest, Sha512 as Inner};

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
}
