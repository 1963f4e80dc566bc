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

/// Domain separation of the derivations: each use of the key hashes its own prefix, and
/// every input under one key starts with an 8-byte word no other use starts with — a frame
/// tag's [`TagContext`] (an epoch counter below 2³², `TLnonceF`, `TLnonceM`, or all ones)
/// or the ASCII `TauLink/` of a derivation — so no tag coincides with a derived value or
/// with a tag of another kind.
const DOMAIN_LINK_KEY: &[u8] = b"TauLink/2 link-key";
const DOMAIN_EPOCH_KEY: &[u8] = b"TauLink/2 epoch-key";
const DOMAIN_REKEY: &[u8] = b"TauLink/2 rekey";
const DOMAIN_FINGERPRINT: &[u8] = b"TauLink/1 fingerprint";

/// What a sealed frame's tag covers besides the frame's bytes (spec §12.2): its place in the
/// link's history, which never travels whole, so a frame recorded anywhere else fails.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TagContext {
    /// A frame of an epoch, under the epoch's key: `wraps₂₄ ‖ slot₈` (below 2³²).
    Counter(u64),
    /// The follower's epoch nonce, under the link key (the frame names nonce and slot).
    FollowerNonce,
    /// The master's epoch nonce, under the link key, bound to the follower's nonce it
    /// answers (which the frame does not carry: only that follower can check it).
    MasterNonce {
        /// The follower's nonce.
        follower_nonce: u64,
    },
    /// An uplink before any epoch, under the link key: no follower checks anything under
    /// it (it gives timing only).
    BeforeEpoch,
}

impl TagContext {
    /// The bytes the tag covers ahead of the frame (8, or 16 for a master's nonce), and how
    /// many of `buf` they fill.
    fn encode(&self, buf: &mut [u8; 16]) -> usize {
        let (head, tail) = buf.split_at_mut(8);
        match self {
            TagContext::Counter(counter) => head.copy_from_slice(&counter.to_le_bytes()),
            TagContext::FollowerNonce => head.copy_from_slice(b"TLnonceF"),
            TagContext::MasterNonce { follower_nonce } => {
                head.copy_from_slice(b"TLnonceM");
                tail.copy_from_slice(&follower_nonce.to_le_bytes());
                return 16;
            }
            TagContext::BeforeEpoch => head.copy_from_slice(&[0xFF; 8]),
        }
        8
    }
}

impl LinkKey {
    /// The key from its 16 bytes.
    pub const fn from_bytes(bytes: [u8; KEY_BYTES]) -> Self {
        Self(bytes)
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

    /// The key of the link whose bind ID is `bind_id`, when this is a module's own key
    /// (spec §12.1, §12.6): two PRF outputs of this key over the bind ID (halves 0 and 1). A
    /// module hands each receiver its link's key at bind and flies it; each model's link
    /// (model match mixes the model into the bind ID) so has its own key, and one link's key
    /// tells nothing of the module's or of another link's. Forging under a link key is as
    /// hard as under this one (2⁻³² per frame).
    pub fn for_link(&self, bind_id: u32) -> Self {
        let half =
            |n: u8| sip(&self.0, &[DOMAIN_LINK_KEY, &bind_id.to_le_bytes(), &[n]]).to_le_bytes();
        let mut bytes = [0u8; KEY_BYTES];
        let (lo, hi) = bytes.split_at_mut(8);
        lo.copy_from_slice(&half(0));
        hi.copy_from_slice(&half(1));
        Self(bytes)
    }

    /// The key of one epoch (spec §12.2): two PRF outputs of this key over the follower's
    /// 64-bit nonce and the master's (halves 0 and 1). Every frame of the epoch is tagged
    /// with it, so an epoch's tags repeat only if *both* nonces repeat: a replayed old
    /// follower nonce meets a fresh master nonce (and the other way round), and nothing
    /// recorded under an earlier epoch verifies. Derived once per handshake; the per-frame
    /// tag costs the same.
    pub fn epoch_key(&self, follower_nonce: u64, master_nonce: u64) -> Self {
        let half = |n: u8| {
            let (f, m) = (follower_nonce.to_le_bytes(), master_nonce.to_le_bytes());
            sip(&self.0, &[DOMAIN_EPOCH_KEY, &f, &m, &[n]]).to_le_bytes()
        };
        let mut bytes = [0u8; KEY_BYTES];
        let (lo, hi) = bytes.split_at_mut(8);
        lo.copy_from_slice(&half(0));
        hi.copy_from_slice(&half(1));
        Self(bytes)
    }

    /// The 32-bit tag of `frame` sent in `context` (for a frame of an epoch, the on-air 8-bit
    /// slot extended by the wraps both ends count): the low half of SipHash-2-4(key,
    /// context ‖ frame). A forger without the key is right with probability 2⁻³² per frame.
    pub fn tag_in(&self, context: &TagContext, frame: &[u8]) -> u32 {
        let mut buf = [0u8; 16];
        let len = context.encode(&mut buf);
        sip(&self.0, &[buf.get(..len).unwrap_or_default(), frame]) as u32
    }

    /// Checks a received tag, in time independent of where it differs.
    pub fn verify_in(&self, context: &TagContext, frame: &[u8], tag: u32) -> bool {
        (self.tag_in(context, frame) ^ tag) == 0
    }

    /// [`LinkKey::tag_in`] of a frame of an epoch under frame counter `counter`.
    pub fn tag(&self, counter: u64, frame: &[u8]) -> u32 {
        self.tag_in(&TagContext::Counter(counter), frame)
    }

    /// [`LinkKey::verify_in`] of a frame of an epoch under frame counter `counter`.
    pub fn verify(&self, counter: u64, frame: &[u8], tag: u32) -> bool {
        self.verify_in(&TagContext::Counter(counter), frame, tag)
    }

    /// An epoch key's proof, in a follower's new nonce frame, that the follower was in force
    /// under this epoch (spec §12.2): the low 32 bits of SipHash-2-4(epoch key,
    /// "TauLink/2 rekey" ‖ new nonce ‖ slot). A master takes a new nonce at once from the
    /// follower of its epoch, and only after the epoch went quiet from anyone else.
    pub fn rekey_proof(&self, new_nonce: u64, slot: u8) -> u32 {
        sip(&self.0, &[DOMAIN_REKEY, &new_nonce.to_le_bytes(), &[slot]]) as u32
    }

    pub(crate) fn prf(&self, domain: &[u8]) -> u64 {
        sip(&self.0, &[domain])
    }
}

/// SipHash-2-4 of `parts`, in order, under `key`: the one copy of the hasher in an image,
/// for the per-frame tag and for the derivations and MACs that run once per bind,
/// handshake, rekey or settings change (keys, PRFs, rekey proofs, the phone's signed
/// changes, the change records). Each inlined copy of the hasher is ≈ 1.2 KB of flash
/// (issue 33); the call and the loop over the parts cost a frame's tag a few instructions.
#[inline(never)]
pub(crate) fn sip(key: &[u8; KEY_BYTES], parts: &[&[u8]]) -> u64 {
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
    fn link_keys_are_distinct_one_way_derivations() {
        let key = LinkKey::from_bytes(reference_key());
        let k3 = key.for_link(3);
        assert_eq!(k3, key.for_link(3));
        assert_ne!(k3, key);
        assert_ne!(k3, key.for_link(4));
        assert_ne!(k3, key.for_link(3).for_link(3));
        assert_ne!(k3.fingerprint(), key.fingerprint());
        // Its halves are SipHash(key, domain ‖ bind ID ‖ half).
        let mut msg = DOMAIN_LINK_KEY.to_vec();
        msg.extend([3, 0, 0, 0, 0]);
        assert_eq!(
            k3.to_bytes()[..8],
            siphash(&reference_key(), &msg).to_le_bytes()
        );
        // A tag under one link's key does not verify under another's.
        let tag = k3.tag(9, b"frame");
        assert!(k3.verify(9, b"frame", tag));
        assert!(!key.for_link(4).verify(9, b"frame", tag));
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

    #[test]
    fn the_fingerprint_is_one_more_separate_value() {
        let key = LinkKey::from_bytes(reference_key());
        let mut other = reference_key();
        other[15] ^= 1;
        assert_ne!(key.fingerprint(), LinkKey::from_bytes(other).fingerprint());
        assert_eq!(format!("{}", Fingerprint(0x1a2b_003d)), "1a2b-003d");
    }

    #[test]
    fn tags_of_other_contexts_and_keys_differ_and_the_key_is_never_printed() {
        let key = LinkKey::from_bytes(reference_key());
        let frame = [0x44u8, 7, 1, 2, 3];
        let contexts = [
            TagContext::Counter(0),
            TagContext::Counter(1 << 8),
            TagContext::FollowerNonce,
            TagContext::MasterNonce { follower_nonce: 9 },
            TagContext::MasterNonce { follower_nonce: 10 },
            TagContext::BeforeEpoch,
        ];
        let tags: Vec<u32> = contexts.iter().map(|c| key.tag_in(c, &frame)).collect();
        for (i, a) in tags.iter().enumerate() {
            assert!(key.verify_in(&contexts[i], &frame, *a));
            for b in &tags[i + 1..] {
                assert_ne!(a, b, "{:?}", contexts[i]);
            }
        }
        // The proof of an epoch names the new nonce and the slot.
        let proof = key.rekey_proof(5, 9);
        assert_ne!(proof, key.rekey_proof(6, 9));
        assert_ne!(proof, key.rekey_proof(5, 10));
        assert_ne!(proof, LinkKey::from_bytes([1; 16]).rekey_proof(5, 9));
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
