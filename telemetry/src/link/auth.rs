//! Link authentication primitives (spec §12): the 128-bit link key, SipHash-2-4 as the MAC
//! of air frames truncated to a 32-bit tag over a never-repeating 64-bit frame counter and
//! the frame, and the one-way derivations of the link's public identity (bind ID, hop
//! seed) from the key, so hearing them reveals nothing of it.
//!
//! SipHash-2-4 (Aumasson & Bernstein, 2012) because it is a PRF designed for short inputs:
//! a 31-byte frame plus the counter is five compression rounds, a few hundred Cortex-M4
//! instructions and no tables (measured in `tests/m4-bench`, `auth`); AES-CMAC would need the
//! nRF52840's ECB peripheral on one end and a software AES on the F405, Poly1305 a one-time
//! key per frame. Written out here (about forty lines, checked against the reference
//! vectors of the SipHash paper) to keep the no_std crate free of dependencies.

/// Bytes of the link key.
pub const KEY_BYTES: usize = 16;
/// Bytes of the truncated tag every authenticated frame carries.
pub const TAG_BYTES: usize = 4;

/// The link's 128-bit secret. Never sent on air; `Debug` does not print it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct LinkKey([u8; KEY_BYTES]);

impl core::fmt::Debug for LinkKey {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("LinkKey(..)")
    }
}

/// Domain separation of the derivations: each use of the key hashes its own prefix. A frame
/// tag hashes its 64-bit counter first; "TauLink/" read as a counter is above 2⁶¹, which no
/// link ever reaches, so no frame tag coincides with a derived value.
const DOMAIN_BIND_ID: &[u8] = b"TauLink/1 bind-id";
/// Domain prefix of the binding-phrase hash (spec §12.2).
const DOMAIN_PHRASE: &[u8] = b"TauLink/1 binding phrase\0";
const DOMAIN_HOP_SEED: &[u8] = b"TauLink/1 hop-seed";
const DOMAIN_MODEL_KEY: &[u8] = b"TauLink/1 model-key";

impl LinkKey {
    /// The key from its 16 bytes.
    pub const fn from_bytes(bytes: [u8; KEY_BYTES]) -> Self {
        Self(bytes)
    }

    /// The key of a binding phrase entered on both ends (ExpressLRS-style, but what it yields
    /// is the key, never sent): `SHA-256("TauLink/1 binding phrase\0" ‖ phrase)[0..16]`.
    pub fn from_phrase(phrase: &str) -> LinkKey {
        let mut h = Sha256::new();
        h.write(DOMAIN_PHRASE);
        h.write(phrase.as_bytes());
        let digest = h.finish();
        let mut key = [0u8; KEY_BYTES];
        for (k, d) in key.iter_mut().zip(digest.iter()) {
            *k = *d;
        }
        Self(key)
    }

    /// The key's bytes (to store it).
    pub const fn to_bytes(&self) -> [u8; KEY_BYTES] {
        self.0
    }

    /// The link's public 32-bit identity (header bytes, bind frames): a PRF of the key, so
    /// one heard frame gives no key bits back (the old header was an invertible mix of the
    /// bind ID). Never 0.
    pub fn bind_id(&self) -> u32 {
        let id = self.prf(DOMAIN_BIND_ID) as u32;
        if id == 0 { 1 } else { id }
    }

    /// The key of radio model `model_id` (model match, spec §12.5): two PRF outputs of this
    /// key over the model ID (halves 0 and 1), so each model's link has its own key, bind ID,
    /// hop seed and tags, and one model's key tells nothing of this key or of another
    /// model's. Forging under a model key is as hard as under this one (2⁻³² per frame).
    pub fn for_model(&self, model_id: u8) -> Self {
        let half = |n: u8| {
            let mut h = SipHasher24::new(&self.0);
            h.write(DOMAIN_MODEL_KEY);
            h.write(&[model_id, n]);
            h.finish().to_le_bytes()
        };
        let mut bytes = [0u8; KEY_BYTES];
        let (lo, hi) = bytes.split_at_mut(8);
        lo.copy_from_slice(&half(0));
        hi.copy_from_slice(&half(1));
        Self(bytes)
    }

    /// The seed of the hop sequence: a PRF of the key, independent of [`LinkKey::bind_id`].
    pub fn hop_seed(&self) -> u32 {
        self.prf(DOMAIN_HOP_SEED) as u32
    }

    /// The 32-bit tag of `frame` sent under frame counter `counter` (the on-air 8-bit slot
    /// extended by the session counter both ends track): the low half of
    /// SipHash-2-4(key, counter LE ‖ frame). A forger without the key is right with
    /// probability 2⁻³² per frame.
    pub fn tag(&self, counter: u64, frame: &[u8]) -> u32 {
        let mut h = SipHasher24::new(&self.0);
        h.write(&counter.to_le_bytes());
        h.write(frame);
        h.finish() as u32
    }

    /// Checks a received tag, in time independent of where it differs.
    pub fn verify(&self, counter: u64, frame: &[u8], tag: u32) -> bool {
        (self.tag(counter, frame) ^ tag) == 0
    }

    fn prf(&self, domain: &[u8]) -> u64 {
        let mut h = SipHasher24::new(&self.0);
        h.write(domain);
        h.finish()
    }
}

/// SHA-256 (FIPS 180-4), fed in pieces; only for hashing a binding phrase, so written for
/// size, not speed.
struct Sha256 {
    state: [u32; 8],
    block: [u8; 64],
    filled: usize,
    length: u64,
}

const SHA256_K: [u32; 64] = [
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
    0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
    0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
    0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
    0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
    0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
    0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2,
];

impl Sha256 {
    fn new() -> Self {
        Self {
            state: [
                0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a, 0x510e527f, 0x9b05688c, 0x1f83d9ab,
                0x5be0cd19,
            ],
            block: [0; 64],
            filled: 0,
            length: 0,
        }
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if let Some(slot) = self.block.get_mut(self.filled) {
                *slot = b;
            }
            self.filled += 1;
            self.length = self.length.wrapping_add(8);
            if self.filled == 64 {
                self.compress();
            }
        }
    }

    fn compress(&mut self) {
        let mut w = [0u32; 64];
        for (word, chunk) in w.iter_mut().zip(self.block.chunks_exact(4)) {
            let mut be = [0u8; 4];
            be.copy_from_slice(chunk);
            *word = u32::from_be_bytes(be);
        }
        for i in 16..64 {
            let at = |j: usize| w.get(j).copied().unwrap_or(0);
            let (w16, w15, w7, w2) = (at(i - 16), at(i - 15), at(i - 7), at(i - 2));
            let s0 = w15.rotate_right(7) ^ w15.rotate_right(18) ^ (w15 >> 3);
            let s1 = w2.rotate_right(17) ^ w2.rotate_right(19) ^ (w2 >> 10);
            if let Some(wi) = w.get_mut(i) {
                *wi = w16.wrapping_add(s0).wrapping_add(w7).wrapping_add(s1);
            }
        }
        let [mut a, mut b, mut c, mut d, mut e, mut f, mut g, mut h] = self.state;
        for (k, wi) in SHA256_K.iter().zip(w.iter()) {
            let s1 = e.rotate_right(6) ^ e.rotate_right(11) ^ e.rotate_right(25);
            let ch = (e & f) ^ (!e & g);
            let t1 = h
                .wrapping_add(s1)
                .wrapping_add(ch)
                .wrapping_add(*k)
                .wrapping_add(*wi);
            let s0 = a.rotate_right(2) ^ a.rotate_right(13) ^ a.rotate_right(22);
            let maj = (a & b) ^ (a & c) ^ (b & c);
            let t2 = s0.wrapping_add(maj);
            h = g;
            g = f;
            f = e;
            e = d.wrapping_add(t1);
            d = c;
            c = b;
            b = a;
            a = t1.wrapping_add(t2);
        }
        for (s, v) in self.state.iter_mut().zip([a, b, c, d, e, f, g, h]) {
            *s = s.wrapping_add(v);
        }
        self.filled = 0;
    }

    fn finish(mut self) -> [u8; 32] {
        let length = self.length;
        self.write(&[0x80]);
        while self.filled != 56 {
            self.write(&[0]);
        }
        self.write(&length.to_be_bytes());
        let mut out = [0u8; 32];
        for (chunk, s) in out.chunks_exact_mut(4).zip(self.state) {
            chunk.copy_from_slice(&s.to_be_bytes());
        }
        out
    }
}

/// SipHash-2-4 with a 64-bit output, fed in pieces.
struct SipHasher24 {
    v: [u64; 4],
    tail: u64,
    ntail: usize,
    length: usize,
}

impl SipHasher24 {
    fn new(key: &[u8; KEY_BYTES]) -> Self {
        let (k0, k1) = key.split_at(8);
        let k0 = u64::from_le_bytes(k0.try_into().unwrap_or([0; 8]));
        let k1 = u64::from_le_bytes(k1.try_into().unwrap_or([0; 8]));
        Self {
            v: [
                k0 ^ 0x736f_6d65_7073_6575,
                k1 ^ 0x646f_7261_6e64_6f6d,
                k0 ^ 0x6c79_6765_6e65_7261,
                k1 ^ 0x7465_6462_7974_6573,
            ],
            tail: 0,
            ntail: 0,
            length: 0,
        }
    }

    fn round(v: &mut [u64; 4]) {
        let [v0, v1, v2, v3] = v;
        *v0 = v0.wrapping_add(*v1);
        *v1 = v1.rotate_left(13) ^ *v0;
        *v0 = v0.rotate_left(32);
        *v2 = v2.wrapping_add(*v3);
        *v3 = v3.rotate_left(16) ^ *v2;
        *v0 = v0.wrapping_add(*v3);
        *v3 = v3.rotate_left(21) ^ *v0;
        *v2 = v2.wrapping_add(*v1);
        *v1 = v1.rotate_left(17) ^ *v2;
        *v2 = v2.rotate_left(32);
    }

    fn compress(&mut self, m: u64) {
        self.v[3] ^= m;
        Self::round(&mut self.v);
        Self::round(&mut self.v);
        self.v[0] ^= m;
    }

    fn write(&mut self, bytes: &[u8]) {
        self.length = self.length.wrapping_add(bytes.len());
        let mut rest = bytes;
        // Top up a partial word byte by byte, then whole words at once (the frame counter
        // is one word, so a frame's bytes arrive word-aligned).
        while self.ntail != 0 {
            let Some((&b, more)) = rest.split_first() else {
                return;
            };
            self.push_byte(b);
            rest = more;
        }
        let mut words = rest.chunks_exact(8);
        for word in &mut words {
            let mut w = [0u8; 8];
            w.copy_from_slice(word);
            self.compress(u64::from_le_bytes(w));
        }
        for &b in words.remainder() {
            self.push_byte(b);
        }
    }

    fn push_byte(&mut self, b: u8) {
        self.tail |= u64::from(b) << (8 * self.ntail);
        self.ntail += 1;
        if self.ntail == 8 {
            self.compress(self.tail);
            self.tail = 0;
            self.ntail = 0;
        }
    }

    fn finish(mut self) -> u64 {
        let last = ((self.length as u64 & 0xFF) << 56) | self.tail;
        self.compress(last);
        self.v[2] ^= 0xFF;
        for _ in 0..4 {
            Self::round(&mut self.v);
        }
        let [v0, v1, v2, v3] = self.v;
        v0 ^ v1 ^ v2 ^ v3
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference_key() -> [u8; 16] {
        core::array::from_fn(|i| i as u8)
    }

    fn siphash(key: &[u8; 16], msg: &[u8]) -> u64 {
        let mut h = SipHasher24::new(key);
        h.write(msg);
        h.finish()
    }

    #[test]
    fn model_keys_are_distinct_one_way_derivations() {
        let key = LinkKey::from_bytes(reference_key());
        let k3 = key.for_model(3);
        assert_eq!(k3, key.for_model(3));
        assert_ne!(k3, key);
        assert_ne!(k3, key.for_model(4));
        assert_ne!(
            k3,
            LinkKey::from_bytes(reference_key())
                .for_model(3)
                .for_model(3)
        );
        assert_ne!(k3.bind_id(), key.bind_id());
        assert_ne!(k3.hop_seed(), key.hop_seed());
        // Its halves are SipHash(key, domain ‖ model ‖ half).
        let mut msg = DOMAIN_MODEL_KEY.to_vec();
        msg.extend([3, 0]);
        assert_eq!(
            k3.to_bytes()[..8],
            siphash(&reference_key(), &msg).to_le_bytes()
        );
        // A tag under one model's key does not verify under another's.
        let tag = k3.tag(9, b"frame");
        assert!(k3.verify(9, b"frame", tag));
        assert!(!key.for_model(4).verify(9, b"frame", tag));
    }

    #[test]
    fn matches_the_reference_vectors_of_the_siphash_paper() {
        let key = reference_key();
        // Paper, appendix A: key 00..0f, message 00..0e (15 bytes).
        let msg: [u8; 15] = core::array::from_fn(|i| i as u8);
        assert_eq!(siphash(&key, &msg), 0xa129_ca61_49be_45e5);
        // Reference implementation's vectors.h, entry 0 (empty message).
        assert_eq!(siphash(&key, &[]), 0x726f_db47_dd0e_0e31);
    }

    #[test]
    fn piecewise_input_hashes_like_one_piece() {
        let key = reference_key();
        let msg: [u8; 40] = core::array::from_fn(|i| (i * 7) as u8);
        for split in 0..msg.len() {
            let (a, b) = msg.split_at(split);
            let mut h = SipHasher24::new(&key);
            h.write(a);
            h.write(b);
            assert_eq!(h.finish(), siphash(&key, &msg), "split at {split}");
        }
    }

    #[test]
    fn a_tag_depends_on_key_counter_and_every_frame_bit() {
        let key = LinkKey::from_bytes(reference_key());
        let frame: [u8; 29] = core::array::from_fn(|i| i as u8);
        let tag = key.tag(7, &frame);
        assert!(key.verify(7, &frame, tag));
        assert!(!key.verify(8, &frame, tag), "another counter: a replay");
        let mut other = reference_key();
        other[15] ^= 1;
        assert!(!LinkKey::from_bytes(other).verify(7, &frame, tag));
        for bit in 0..frame.len() * 8 {
            let mut f = frame;
            f[bit / 8] ^= 1 << (bit % 8);
            assert!(!key.verify(7, &f, tag), "bit {bit}");
        }
    }

    fn sha256(msg: &[u8]) -> [u8; 32] {
        let mut h = Sha256::new();
        h.write(msg);
        h.finish()
    }

    fn hex(bytes: &[u8]) -> String {
        bytes.iter().map(|b| format!("{b:02x}")).collect()
    }

    #[test]
    fn sha256_matches_the_fips_vectors() {
        assert_eq!(
            hex(&sha256(b"abc")),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(
            hex(&sha256(&[b'a'; 1000])),
            "41edece42d63e8d9bf515a9ba6932e1c20cbc9f5a5d134645adb5db1b9737ea3"
        );
    }

    /// Known answers from Python's hashlib:
    /// `hashlib.sha256(b"TauLink/1 binding phrase\0" + phrase).digest()[:16]`.
    #[test]
    fn a_binding_phrase_gives_the_key_hashlib_computes() {
        assert_eq!(
            hex(&LinkKey::from_phrase("correct horse battery staple").to_bytes()),
            "6c8c3067ce51b390ad2a8164c0352019"
        );
        assert_eq!(
            hex(&LinkKey::from_phrase("").to_bytes()),
            "ae05de4532b5d44cfd7dffc4082d46e6"
        );
    }

    #[test]
    fn identity_and_hop_seed_are_separate_one_way_values_of_the_key() {
        let key = LinkKey::from_bytes(reference_key());
        assert_ne!(key.bind_id(), key.hop_seed());
        assert_ne!(u64::from(key.bind_id()), key.tag(0, &[]) as u64);
        let mut other = reference_key();
        other[0] ^= 0x80;
        let other = LinkKey::from_bytes(other);
        assert_ne!(key.bind_id(), other.bind_id());
        assert_ne!(key.hop_seed(), other.hop_seed());
        assert_eq!(
            format!("{key:?}"),
            "LinkKey(..)",
            "the key is never printed"
        );
    }
}

#[cfg(test)]
mod budget {
    use crate::channels::ChannelFormat;
    use crate::frame::{CRC_BYTES, uplink_overhead};
    use crate::link::rate::{RateMode, airtime_us};

    use super::TAG_BYTES;

    /// The airtime cost of the 4-byte tag at F500 (spec §12): the 16-channel uplink grows
    /// from 29 to 31 bytes, still inside F500's 32-byte frame, so the slot and the channel
    /// update rate stay as they are; only stream room shrinks by two bytes.
    #[test]
    fn a_tagged_16_channel_uplink_still_fits_f500s_frame() {
        let rate = RateMode::F500;
        let crc_uplink = uplink_overhead(ChannelFormat::Full16, false);
        let tagged = crc_uplink - CRC_BYTES + TAG_BYTES;
        assert_eq!((crc_uplink, tagged), (29, 31));
        assert!(tagged <= rate.max_frame_bytes());
        let (before, after) = (
            airtime_us(crc_uplink, rate.bit_rate_bps()),
            airtime_us(tagged, rate.bit_rate_bps()),
        );
        assert_eq!((before, after), (1344, 1407), "µs on air");
        // One slot in four is a downlink: channel updates per second.
        assert_eq!(rate.slot_rate_hz() * 3 / 4, 375);
    }
}
