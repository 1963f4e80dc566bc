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

#[cfg(feature = "defmt")]
impl defmt::Format for LinkKey {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "LinkKey(..)");
    }
}

/// A key's fingerprint ([`LinkKey::fingerprint`]); shown as `1a2b-3c4d`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fingerprint(pub u32);

impl core::fmt::Display for Fingerprint {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:04x}-{:04x}", self.0 >> 16, self.0 & 0xFFFF)
    }
}

/// Longest binding phrase, bytes of UTF-8.
pub const PHRASE_MAX_BYTES: usize = 64;

/// Domain prefix of the phrase hash (spec §12); the NUL ends it, so no phrase can extend it.
const DOMAIN_PHRASE: &[u8] = b"TauLink/1 binding phrase\0";

/// Why a binding phrase was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PhraseError {
    /// Longer than [`PHRASE_MAX_BYTES`] bytes.
    TooLong,
    /// Holds a control character (a phrase must be typeable the same on both ends).
    NotPrintable,
}

impl core::fmt::Display for PhraseError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            PhraseError::TooLong => "binding phrase longer than 64 bytes",
            PhraseError::NotPrintable => "binding phrase holds a control character",
        })
    }
}

impl core::error::Error for PhraseError {}

/// The key of a binding phrase as a person typed it, the one rule both ends (and the
/// ground station) apply: leading and trailing white space is dropped; what is left must be
/// at most [`PHRASE_MAX_BYTES`] bytes of printable UTF-8 (spaces inside are part of it).
/// `Ok(None)`: no phrase (empty), the link runs unauthenticated.
pub fn key_for_phrase(text: &str) -> Result<Option<LinkKey>, PhraseError> {
    let phrase = text.trim();
    if phrase.is_empty() {
        return Ok(None);
    }
    if phrase.len() > PHRASE_MAX_BYTES {
        return Err(PhraseError::TooLong);
    }
    if phrase.chars().any(char::is_control) {
        return Err(PhraseError::NotPrintable);
    }
    Ok(Some(LinkKey::from_phrase(phrase)))
}

/// Domain separation of the derivations: each use of the key hashes its own prefix. A frame
/// tag hashes its 64-bit counter first; "TauLink/" read as a counter is above 2⁶¹, which no
/// link ever reaches, so no frame tag coincides with a derived value.
const DOMAIN_BIND_ID: &[u8] = b"TauLink/1 bind-id";
/// Domain prefix of the binding-phrase hash (spec §12.2).
const DOMAIN_HOP_SEED: &[u8] = b"TauLink/1 hop-seed";
const DOMAIN_MODEL_KEY: &[u8] = b"TauLink/1 model-key";
const DOMAIN_EPOCH_KEY: &[u8] = b"TauLink/1 epoch-key";
const DOMAIN_FINGERPRINT: &[u8] = b"TauLink/1 fingerprint";

impl LinkKey {
    /// The key from its 16 bytes.
    pub const fn from_bytes(bytes: [u8; KEY_BYTES]) -> Self {
        Self(bytes)
    }

    /// The key of a binding phrase: `SHA-256("TauLink/1 binding phrase\0" ‖ phrase)`, its
    /// first 16 bytes (spec §12). The phrase's bytes are hashed as given; people's input goes
    /// through [`key_for_phrase`], which trims and checks it first.
    pub fn from_phrase(phrase: &str) -> LinkKey {
        use sha2::Digest;
        let mut h = sha2::Sha256::new();
        h.update(DOMAIN_PHRASE);
        h.update(phrase.as_bytes());
        let digest: [u8; 32] = h.finalize().into();
        let mut key = [0u8; KEY_BYTES];
        for (k, d) in key.iter_mut().zip(digest) {
            *k = d;
        }
        LinkKey(key)
    }

    /// A short public check value of the key, for a person to compare both ends (console,
    /// handset menu, ground station): the low 32 bits of SipHash-2-4(key,
    /// "TauLink/1 fingerprint"). One-way like the bind ID, and a different value from it.
    pub fn fingerprint(&self) -> Fingerprint {
        Fingerprint(self.prf(DOMAIN_FINGERPRINT) as u32)
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

    /// The key of radio model `model_id` (model match, spec §12.6): two PRF outputs of this
    /// key over the model ID (halves 0 and 1), so each model's link has its own key, bind ID,
    /// hop seed and tags, and one model's key tells nothing of this key or of another
    /// model's. Forging under a model key is as hard as under this one (2⁻³² per frame).
    pub fn for_model(&self, model_id: u8) -> Self {
        let half = |n: u8| sip_cold(&self.0, &[DOMAIN_MODEL_KEY, &[model_id, n]]).to_le_bytes();
        let mut bytes = [0u8; KEY_BYTES];
        let (lo, hi) = bytes.split_at_mut(8);
        lo.copy_from_slice(&half(0));
        hi.copy_from_slice(&half(1));
        Self(bytes)
    }

    /// The key of one epoch (spec §12.2): two PRF outputs of this key over the follower's
    /// nonce and the master's (halves 0 and 1). Every frame of the epoch is tagged with it,
    /// so an epoch's tags repeat only if *both* nonces repeat: a replayed old follower nonce
    /// meets a fresh master nonce (and the other way round), and nothing recorded under an
    /// earlier epoch verifies. Derived once per handshake; the per-frame tag costs the same.
    pub fn epoch_key(&self, follower_nonce: u32, master_nonce: u32) -> Self {
        let half = |n: u8| {
            let (f, m) = (follower_nonce.to_le_bytes(), master_nonce.to_le_bytes());
            sip_cold(&self.0, &[DOMAIN_EPOCH_KEY, &f, &m, &[n]]).to_le_bytes()
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

    pub(crate) fn prf(&self, domain: &[u8]) -> u64 {
        sip_cold(&self.0, &[domain])
    }
}

/// SipHash-2-4 of `parts`, in order, under `key`: one out-of-line copy for the derivations
/// and MACs that run once per bind, handshake or settings change (keys, PRFs, the phone's
/// signed changes, the change records).
/// The hasher is forced inline for the per-frame tag, and each inlined copy is ≈ 1.2 KB of
/// flash (issue 33).
#[inline(never)]
pub(crate) fn sip_cold(key: &[u8; KEY_BYTES], parts: &[&[u8]]) -> u64 {
    let mut h = SipHasher24::new(key);
    for part in parts {
        h.write(part);
    }
    h.finish()
}

/// SipHash-2-4 with a 64-bit output, fed in pieces.
pub(crate) struct SipHasher24 {
    v: [u64; 4],
    tail: u64,
    ntail: usize,
    length: usize,
}

impl SipHasher24 {
    #[inline(always)]
    pub(crate) fn new(key: &[u8; KEY_BYTES]) -> Self {
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

    #[inline(always)]
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

    #[inline(always)]
    fn compress(&mut self, m: u64) {
        self.v[3] ^= m;
        Self::round(&mut self.v);
        Self::round(&mut self.v);
        self.v[0] ^= m;
    }

    #[inline(always)]
    pub(crate) fn write(&mut self, bytes: &[u8]) {
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

    #[inline(always)]
    fn push_byte(&mut self, b: u8) {
        self.tail |= u64::from(b) << (8 * self.ntail);
        self.ntail += 1;
        if self.ntail == 8 {
            self.compress(self.tail);
            self.tail = 0;
            self.ntail = 0;
        }
    }

    #[inline(always)]
    pub(crate) fn finish(mut self) -> u64 {
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

    fn bytes(hex: &str) -> [u8; 16] {
        core::array::from_fn(|i| u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).unwrap())
    }

    #[test]
    fn a_phrase_gives_the_key_of_the_spec() {
        // Expected keys from Python, not from this code:
        // hashlib.sha256(b"TauLink/1 binding phrase\0" + p).hexdigest()[:32]
        for (phrase, key) in [
            (
                "correct horse battery staple",
                "6c8c3067ce51b390ad2a8164c0352019",
            ),
            ("a", "6882b94b07dd0f2059789153d1c32eb0"),
            ("Grüezi Säntis 2026", "474c6b9d03a2946f351696fdb431fdef"),
            (
                "xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx",
                "29b16b08d9347165626b1aa44e39481d",
            ),
        ] {
            assert_eq!(
                LinkKey::from_phrase(phrase).to_bytes(),
                bytes(key),
                "{phrase}"
            );
            assert_eq!(
                key_for_phrase(&format!("  {phrase}\t")),
                Ok(Some(LinkKey::from_bytes(bytes(key)))),
                "typed with white space around it"
            );
        }
    }

    #[test]
    fn phrase_rules_one_to_64_printable_bytes_empty_is_none() {
        assert_eq!(key_for_phrase(""), Ok(None));
        assert_eq!(key_for_phrase("   "), Ok(None));
        assert!(
            key_for_phrase(&"é".repeat(32)).unwrap().is_some(),
            "64 bytes"
        );
        assert_eq!(
            key_for_phrase(&"é".repeat(32).replace('é', "ée")),
            Err(PhraseError::TooLong)
        );
        assert_eq!(key_for_phrase(&"x".repeat(65)), Err(PhraseError::TooLong));
        assert_eq!(
            key_for_phrase("bell\u{7}ring"),
            Err(PhraseError::NotPrintable)
        );
        assert_eq!(key_for_phrase("two\nlines"), Err(PhraseError::NotPrintable));
        // Inner spaces and case count.
        assert_ne!(key_for_phrase("a b"), key_for_phrase("ab"));
        assert_ne!(key_for_phrase("A"), key_for_phrase("a"));
    }

    #[test]
    fn the_fingerprint_is_one_more_separate_value() {
        let key = LinkKey::from_phrase("correct horse battery staple");
        assert_ne!(key.fingerprint().0, key.bind_id());
        assert_ne!(key.fingerprint().0, key.hop_seed());
        assert_ne!(
            key.fingerprint(),
            LinkKey::from_phrase("correct horse battery stapler").fingerprint()
        );
        assert_eq!(format!("{}", Fingerprint(0x1a2b_003d)), "1a2b-003d");
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
