//! The epoch every authenticated frame is tagged in (spec §12.2) and its 64-bit counter
//! `nonce₃₂ ‖ wraps₂₄ ‖ slot₈`, and how both ends agree on them without sending more than
//! the 8-bit slot per frame. The follower draws a random nonce N at every (re)acquisition
//! and sends it in [`Frame::Nonce`](crate::frame::Frame::Nonce) downlinks; the master adopts
//! a verified one, draws its own fresh nonce M and sends it back in a
//! [`Frame::MasterNonce`](crate::frame::Frame::MasterNonce) uplink tagged under N. From then
//! both tag with the epoch key of (N, M) ([`LinkKey::epoch_key`]) and, from the wrap of the
//! slot counter in which N was sent, count the wraps on their own slot grids. An epoch's
//! tags repeat only if both nonces do: each end's own fresh nonce protects it, so a frame
//! recorded 256 slots (or any number of slots) earlier, before either end restarted, or
//! under any earlier epoch however old, fails its tag.
//!
//! Nothing is stored across a reboot (flash wear): freshness comes from each end's nonces,
//! drawn from a seed its application injects (a hardware RNG) and the time.

use crate::link::auth::LinkKey;

/// Slot-counter wraps an epoch may count (24 bits) before the follower draws a new nonce:
/// 2³² slots, 99 days at 500 slots/s.
pub(crate) const WRAPS_LIMIT: u32 = 1 << 24;
/// Follower nonces a master remembers having used, so a replayed handshake of the same
/// session is refused at once rather than breaking the link for a re-acquisition (an
/// availability measure: the master's own nonce already keeps every replay from verifying).
const RECENT_NONCES: usize = 8;

/// The frame counter of `slot` in wrap `wraps` of epoch `nonce`: `nonce₃₂ ‖ wraps₂₄ ‖ slot₈`.
/// A [`Frame::Nonce`](crate::frame::Frame::Nonce) is tagged under `counter(nonce, 0, slot)`.
pub const fn counter(nonce: u32, wraps: u32, slot: u8) -> u64 {
    ((nonce as u64) << 32) | (((wraps & (WRAPS_LIMIT - 1)) as u64) << 8) | slot as u64
}

/// Fresh epoch nonces: SplitMix64 over a seed the application injects (its hardware RNG at
/// boot), stirred with the time of every draw, so a controller that reboots without a seed
/// still does not repeat the nonce of its previous boot unless it locks at the same
/// microsecond. Never 0 (the master's "no epoch") and never the previous nonce.
#[derive(Clone, Debug)]
pub(crate) struct NonceSource {
    state: u64,
    last: u32,
}

impl NonceSource {
    pub(crate) const fn new(seed: u64) -> Self {
        Self {
            state: seed,
            last: 0,
        }
    }

    pub(crate) fn draw(&mut self, now_us: u64) -> u32 {
        loop {
            self.state = self
                .state
                .wrapping_add(0x9E37_79B9_7F4A_7C15)
                .wrapping_add(now_us.rotate_left(29));
            let mut z = self.state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            let nonce = (z ^ (z >> 31)) as u32;
            if nonce != 0 && nonce != self.last {
                self.last = nonce;
                return nonce;
            }
        }
    }
}

/// The follower's side of the epoch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FollowerEpoch {
    /// Not on the grid: no nonce.
    None,
    /// On the master's grid by timing only; `nonce` is sent in every downlink slot of the
    /// current wrap (wraps 0) until the master's nonce comes back under it.
    Handshake { nonce: u32 },
    /// Both nonces known: frames are tagged with `key`, the epoch key of (`nonce`, the
    /// master's nonce); `wraps` slot-counter wraps since the handshake's.
    InForce {
        nonce: u32,
        master_nonce: u32,
        key: LinkKey,
        wraps: u32,
    },
}

impl FollowerEpoch {
    /// The counter of `slot` (the slot being tracked), if there is a nonce.
    pub(crate) fn counter(&self, slot: u8) -> Option<u64> {
        match *self {
            FollowerEpoch::None => None,
            FollowerEpoch::Handshake { nonce } => Some(counter(nonce, 0, slot)),
            FollowerEpoch::InForce { nonce, wraps, .. } => Some(counter(nonce, wraps, slot)),
        }
    }

    /// The key frames of the epoch are tagged with: the epoch key once in force, the link
    /// key during the handshake (nonce frames both ways), none without a nonce.
    pub(crate) fn key<'a>(&'a self, link: &'a LinkKey) -> Option<&'a LinkKey> {
        match self {
            FollowerEpoch::None => None,
            FollowerEpoch::Handshake { .. } => Some(link),
            FollowerEpoch::InForce { key, .. } => Some(key),
        }
    }

    /// The grid moved on to `next_slot`. At a wrap of the slot counter an epoch in force
    /// counts it (and is replaced by a new handshake when the 24 bits are used up); a
    /// handshake still waiting draws a new nonce, so a nonce is only ever sent within one
    /// wrap, where its frames' counters are all distinct.
    pub(crate) fn advance(&mut self, next_slot: u8, nonces: &mut NonceSource, now_us: u64) {
        if next_slot != 0 {
            return;
        }
        *self = match *self {
            FollowerEpoch::None => FollowerEpoch::None,
            FollowerEpoch::InForce {
                nonce,
                master_nonce,
                key,
                wraps,
            } if wraps + 1 < WRAPS_LIMIT => FollowerEpoch::InForce {
                nonce,
                master_nonce,
                key,
                wraps: wraps + 1,
            },
            FollowerEpoch::InForce { .. } | FollowerEpoch::Handshake { .. } => {
                FollowerEpoch::Handshake {
                    nonce: nonces.draw(now_us),
                }
            }
        };
    }
}

/// The epoch a master adopted.
#[derive(Clone, Copy, Debug)]
struct Adopted {
    /// The follower's nonce.
    nonce: u32,
    /// The master's own, drawn at adoption.
    master_nonce: u32,
    /// The epoch key of both.
    key: LinkKey,
    /// Master slot at which wrap 0 began.
    base: u32,
}

/// The master's side of the epoch.
#[derive(Clone, Debug)]
pub(crate) struct MasterEpoch {
    current: Option<Adopted>,
    /// Nonces used before `current` (0 = empty).
    recent: [u32; RECENT_NONCES],
    next_recent: usize,
    /// Master slot of the last downlink verified under `current`.
    last_heard: Option<u32>,
    /// The master's nonces.
    nonces: NonceSource,
}

/// What the master made of a verified [`Frame::Nonce`](crate::frame::Frame::Nonce).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum NonceVerdict {
    /// A new epoch from now on.
    Adopted,
    /// The nonce already in use, repeated in its own wrap by a follower that has not yet
    /// heard an uplink under it.
    Repeated,
    /// Refused: a nonce used before (a replay), the current one outside its wrap 0 (a
    /// replay), or the current epoch was heard in the last downlink slot (a follower in
    /// force does not send nonces: a replay from before this master booted).
    Refused,
}

impl MasterEpoch {
    pub(crate) const fn new(seed: u64) -> Self {
        Self {
            current: None,
            recent: [0; RECENT_NONCES],
            next_recent: 0,
            last_heard: None,
            nonces: NonceSource::new(seed),
        }
    }

    /// Whether an epoch is in use.
    pub(crate) fn active(&self) -> bool {
        self.current.is_some()
    }

    /// The counter of master slot `slot`: under the current epoch, or (before any) the
    /// bare slot, which no follower verifies (its nonces are never 0).
    pub(crate) fn counter(&self, slot: u32) -> u64 {
        match self.current {
            Some(e) => counter(e.nonce, slot.wrapping_sub(e.base) >> 8, slot as u8),
            None => counter(0, 0, slot as u8),
        }
    }

    /// The epoch key, if an epoch is in use.
    pub(crate) fn key(&self) -> Option<&LinkKey> {
        self.current.as_ref().map(|e| &e.key)
    }

    /// (follower's nonce, master's nonce) of the epoch in use.
    pub(crate) fn nonces(&self) -> Option<(u32, u32)> {
        self.current.map(|e| (e.nonce, e.master_nonce))
    }

    /// The master's nonce and the counter to tag it under (`N ‖ 0 ‖ slot`), if `slot` is in
    /// the wrap the follower's nonce was sent in — the only one in which the follower can
    /// check it (a handshake never outlives its wrap).
    pub(crate) fn master_nonce_for(&self, slot: u32) -> Option<(u32, u64)> {
        let e = self.current?;
        (slot.wrapping_sub(e.base) < 256).then(|| (e.master_nonce, counter(e.nonce, 0, slot as u8)))
    }

    /// The master moved on to `slot`: an epoch whose 2³² slots are used up is retired.
    pub(crate) fn on_slot(&mut self, slot: u32) {
        if let Some(e) = self.current
            && slot == e.base
        {
            self.retire(e.nonce);
        }
    }

    /// A downlink verified under the current epoch in `slot`.
    pub(crate) fn heard(&mut self, slot: u32) {
        self.last_heard = Some(slot);
    }

    /// A verified nonce frame in downlink slot `slot`, downlinks every `ratio` slots, at
    /// `now_us`. Adopting draws the master's own nonce and derives the epoch key from `link`.
    pub(crate) fn offer(
        &mut self,
        nonce: u32,
        slot: u32,
        ratio: u8,
        link: &LinkKey,
        now_us: u64,
    ) -> NonceVerdict {
        if let Some(e) = self.current
            && e.nonce == nonce
        {
            return if slot.wrapping_sub(e.base) < 256 {
                NonceVerdict::Repeated
            } else {
                NonceVerdict::Refused
            };
        }
        let live = self
            .last_heard
            .is_some_and(|s| slot.wrapping_sub(s) <= u32::from(ratio));
        if live || self.recent.contains(&nonce) {
            return NonceVerdict::Refused;
        }
        if let Some(old) = self.current {
            self.retire(old.nonce);
        }
        let master_nonce = self.nonces.draw(now_us);
        self.current = Some(Adopted {
            nonce,
            master_nonce,
            key: link.epoch_key(nonce, master_nonce),
            base: slot & !0xFF,
        });
        NonceVerdict::Adopted
    }

    fn retire(&mut self, nonce: u32) {
        if let Some(r) = self.recent.get_mut(self.next_recent) {
            *r = nonce;
        }
        self.next_recent = (self.next_recent + 1) % RECENT_NONCES;
        self.current = None;
        self.last_heard = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_counter_is_epoch_then_wraps_then_slot() {
        assert_eq!(counter(0xA1B2_C3D4, 0x12_3456, 0x78), 0xA1B2_C3D4_1234_5678);
        assert_eq!(counter(1, 0, 0), 1 << 32);
    }

    #[test]
    fn nonces_are_never_zero_nor_repeated_back_to_back_and_depend_on_seed_and_time() {
        let mut a = NonceSource::new(7);
        let mut b = NonceSource::new(7);
        let mut c = NonceSource::new(8);
        let xs: Vec<u32> = (0..1000).map(|_| a.draw(5)).collect();
        assert!(xs.iter().all(|&n| n != 0));
        assert!(xs.windows(2).all(|w| w[0] != w[1]));
        assert_eq!(b.draw(5), xs[0], "deterministic for one seed and time");
        assert_ne!(c.draw(5), xs[0], "another seed");
        assert_ne!(NonceSource::new(7).draw(6), xs[0], "another time");
    }

    #[test]
    fn a_follower_epoch_counts_wraps_and_renews_its_nonce_where_it_must() {
        let mut nonces = NonceSource::new(1);
        let key = LinkKey::from_bytes([7; 16]);
        let in_force = |wraps| FollowerEpoch::InForce {
            nonce: 9,
            master_nonce: 3,
            key,
            wraps,
        };
        let mut e = in_force(0);
        e.advance(255, &mut nonces, 0);
        assert_eq!(e.counter(255), Some(counter(9, 0, 255)));
        e.advance(0, &mut nonces, 0);
        assert_eq!(e.counter(0), Some(counter(9, 1, 0)));
        // A handshake never leaves its wrap: a new nonce at the wrap.
        let mut h = FollowerEpoch::Handshake { nonce: 9 };
        h.advance(0, &mut nonces, 0);
        assert!(matches!(h, FollowerEpoch::Handshake { nonce } if nonce != 9));
        // The 24 bits of wraps used up: a new handshake, never a repeated counter.
        let mut e = in_force(WRAPS_LIMIT - 1);
        e.advance(0, &mut nonces, 0);
        assert!(matches!(e, FollowerEpoch::Handshake { nonce } if nonce != 9));
    }

    #[test]
    fn the_master_adopts_fresh_nonces_only() {
        let link = LinkKey::from_bytes([7; 16]);
        let mut m = MasterEpoch::new(1);
        assert_eq!(m.counter(300), counter(0, 0, 44));
        assert_eq!(m.master_nonce_for(300), None);
        // Nonce sent in slot 259 (wrap starting at 256).
        assert_eq!(m.offer(5, 259, 4, &link, 0), NonceVerdict::Adopted);
        let (n, master_nonce) = m.nonces().expect("adopted");
        assert_eq!(n, 5);
        assert_eq!(m.key(), Some(&link.epoch_key(5, master_nonce)));
        assert_eq!(
            m.master_nonce_for(260),
            Some((master_nonce, counter(5, 0, 4)))
        );
        assert_eq!(m.master_nonce_for(512), None, "only in the nonce's wrap");
        assert_eq!(m.counter(260), counter(5, 0, 4));
        assert_eq!(m.counter(512), counter(5, 1, 0));
        assert_eq!(m.offer(5, 263, 4, &link, 0), NonceVerdict::Repeated);
        assert_eq!(
            m.nonces(),
            Some((5, master_nonce)),
            "a repeat keeps the epoch"
        );
        assert_eq!(m.offer(5, 259 + 256, 4, &link, 0), NonceVerdict::Refused);
        // Heard under epoch 5 in the last downlink slot: no new nonce now.
        m.heard(515);
        assert_eq!(m.offer(6, 519, 4, &link, 0), NonceVerdict::Refused);
        assert_eq!(m.offer(6, 523, 4, &link, 0), NonceVerdict::Adopted);
        assert_ne!(
            m.nonces().map(|n| n.1),
            Some(master_nonce),
            "a fresh master nonce"
        );
        // 5 was used: a replay of its handshake is refused.
        assert_eq!(m.offer(5, 1027, 4, &link, 0), NonceVerdict::Refused);
        assert_eq!(m.counter(1028), counter(6, 2, 4));
        // An epoch retires when its slot counter comes round to its wrap 0 (2³² slots).
        m.on_slot(600);
        assert!(m.active());
        m.on_slot(512);
        assert!(!m.active());
    }
}
