//! The epoch every authenticated frame is tagged in (spec §12.2), its counter
//! `wraps₂₄ ‖ slot₈`, and how both ends agree on it without sending more than the 8-bit slot
//! per frame. The follower draws a random 64-bit nonce N at every (re)acquisition and sends
//! it in [`Frame::Nonce`](crate::frame::Frame::Nonce) downlinks; the master adopts a verified
//! one, draws its own fresh 64-bit nonce M and sends it back in a
//! [`Frame::MasterNonce`](crate::frame::Frame::MasterNonce) uplink tagged under N and M. From
//! then both tag with the epoch key of (N, M) ([`LinkKey::epoch_key`]) and, from the wrap of
//! the slot counter in which N was sent, count the wraps on their own slot grids. An epoch's
//! tags repeat only if both nonces do: each end's own fresh nonce protects it.
//!
//! The master keeps the epoch in force ([`MasterEpoch`]'s current one) until the new one is
//! confirmed by a downlink tagged under it, so a replayed nonce frame never takes the link
//! away from a follower flying under the current epoch; while the current epoch is live
//! (heard within the failsafe period) a new nonce is taken only with a proof, made with the
//! current epoch's key, that it comes from that epoch's follower (a follower that resynced);
//! and without one at most one new epoch is adopted per wrap of the slot counter, so a third
//! radio can make the master spend at most one uplink in 256 on a nonce.
//!
//! Nothing is stored across a reboot (flash wear): freshness comes from each end's nonces,
//! drawn from a seed its application injects (a hardware RNG) and the time.

use crate::link::auth::LinkKey;

/// Slot-counter wraps an epoch may count before the follower draws a new nonce and the
/// master retires it: 2²⁴, i.e. 2³² slots (99 days at 500 slots/s), where the master's
/// 32-bit slot counter comes round. Every epoch counter stays below 2³², far from the other
/// tag contexts (spec §12.2).
pub(crate) const WRAPS_LIMIT: u64 = 1 << 24;
/// Follower nonces a master remembers having used, so a replayed handshake of the same
/// session is refused at once (an availability measure: the master's own nonce already keeps
/// every replay from verifying anything old).
const RECENT_NONCES: usize = 8;
/// Slots of one wrap of the on-air slot counter.
const WRAP_SLOTS: u32 = 256;

/// The frame counter of `slot` in wrap `wraps` of an epoch: `wraps₂₄ ‖ slot₈`.
pub const fn counter(wraps: u64, slot: u8) -> u64 {
    ((wraps & (WRAPS_LIMIT - 1)) << 8) | slot as u64
}

/// Fresh 64-bit epoch nonces: SplitMix64 over a seed the application injects (its hardware
/// RNG at boot), stirred with the time of every draw, so a controller that reboots without
/// a seed still does not repeat the nonce of its previous boot unless it locks at the same
/// microsecond. Never 0 and never the previous nonce.
#[derive(Clone, Debug)]
pub(crate) struct NonceSource {
    state: u64,
    last: u64,
}

impl NonceSource {
    pub(crate) const fn new(seed: u64) -> Self {
        Self {
            state: seed,
            last: 0,
        }
    }

    pub(crate) fn draw(&mut self, now_us: u64) -> u64 {
        loop {
            self.state = self
                .state
                .wrapping_add(0x9E37_79B9_7F4A_7C15)
                .wrapping_add(now_us.rotate_left(29));
            let mut z = self.state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            let nonce = z ^ (z >> 31);
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
    Handshake { nonce: u64 },
    /// Both nonces known: frames are tagged with `key`, the epoch key of (`nonce`, the
    /// master's nonce); `wraps` slot-counter wraps since the handshake's.
    InForce {
        nonce: u64,
        master_nonce: u64,
        key: LinkKey,
        wraps: u64,
    },
}

impl FollowerEpoch {
    /// The counter of `slot` (the slot being tracked) in the epoch in force.
    pub(crate) fn counter(&self, slot: u8) -> Option<u64> {
        match *self {
            FollowerEpoch::InForce { wraps, .. } => Some(counter(wraps, slot)),
            FollowerEpoch::None | FollowerEpoch::Handshake { .. } => None,
        }
    }

    /// The epoch key once in force.
    pub(crate) fn key(&self) -> Option<&LinkKey> {
        match self {
            FollowerEpoch::InForce { key, .. } => Some(key),
            FollowerEpoch::None | FollowerEpoch::Handshake { .. } => None,
        }
    }

    /// The grid moved on to `next_slot`. At a wrap of the slot counter an epoch in force
    /// counts it (and is replaced by a new handshake when the wraps are used up); a
    /// handshake still waiting draws a new nonce, so a nonce is only ever sent within one
    /// wrap, where its frames' slots are all distinct.
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

/// An epoch the master adopted.
#[derive(Clone, Copy, Debug)]
struct Adopted {
    /// The follower's nonce.
    nonce: u64,
    /// The master's own, drawn at adoption.
    master_nonce: u64,
    /// The epoch key of both.
    key: LinkKey,
    /// Master slot at which wrap 0 began.
    base: u32,
}

impl Adopted {
    fn counter(&self, slot: u32) -> u64 {
        counter(
            u64::from(slot.wrapping_sub(self.base) / WRAP_SLOTS),
            slot as u8,
        )
    }

    fn in_wrap_zero(&self, slot: u32) -> bool {
        slot.wrapping_sub(self.base) < WRAP_SLOTS
    }
}

/// What the master made of a verified [`Frame::Nonce`](crate::frame::Frame::Nonce).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum NonceVerdict {
    /// A new epoch, pending until a downlink confirms it; the current one stays in force.
    Adopted,
    /// The pending nonce, repeated in its own wrap by a follower that has not yet heard an
    /// uplink under it.
    Repeated,
    /// Refused: a nonce used before (a replay), the pending one outside its wrap 0, the
    /// current epoch live and no proof from its follower, or a new epoch already adopted in
    /// the last wrap without one.
    Refused,
}

/// The master's side of the epoch.
#[derive(Clone, Debug)]
pub(crate) struct MasterEpoch {
    /// The epoch in force: uplinks with channels are tagged with its key.
    current: Option<Adopted>,
    /// Master slot of the last downlink verified under `current` (`None`: never heard).
    current_heard: Option<u32>,
    /// An adopted epoch whose follower has not yet been heard under it, while `current`
    /// stays in force.
    pending: Option<Adopted>,
    /// The last epoch adopted: its master's nonce answers its follower's nonce frames in
    /// their wrap.
    answering: Option<Adopted>,
    /// Nonces used before (0 = empty).
    recent: [u64; RECENT_NONCES],
    next_recent: usize,
    /// Master slot of the last adoption.
    last_adoption: Option<u32>,
    /// Slots within which a heard epoch counts as live (the failsafe period).
    live_slots: u32,
    /// The master's nonces.
    nonces: NonceSource,
    /// Epochs adopted (each one a nonce uplink in place of channels).
    adoptions: u32,
    /// Verified nonce frames refused.
    refused: u32,
}

impl MasterEpoch {
    /// A master epoch whose heard epochs count as live for `live_slots` slots.
    pub(crate) const fn new(seed: u64, live_slots: u32) -> Self {
        Self {
            current: None,
            current_heard: None,
            pending: None,
            answering: None,
            recent: [0; RECENT_NONCES],
            next_recent: 0,
            last_adoption: None,
            live_slots,
            nonces: NonceSource::new(seed),
            adoptions: 0,
            refused: 0,
        }
    }

    /// Whether an epoch is in force.
    pub(crate) fn active(&self) -> bool {
        self.current.is_some()
    }

    /// The counter of master slot `slot` under the epoch in force.
    pub(crate) fn counter(&self, slot: u32) -> Option<u64> {
        self.current.map(|e| e.counter(slot))
    }

    /// The key of the epoch in force.
    pub(crate) fn key(&self) -> Option<&LinkKey> {
        self.current.as_ref().map(|e| &e.key)
    }

    /// (follower's nonce, master's nonce) of the epoch in force.
    pub(crate) fn nonces(&self) -> Option<(u64, u64)> {
        self.current.map(|e| (e.nonce, e.master_nonce))
    }

    /// (follower's nonce, master's nonce) of the pending epoch.
    pub(crate) fn pending_nonces(&self) -> Option<(u64, u64)> {
        self.pending.map(|e| (e.nonce, e.master_nonce))
    }

    /// Epochs adopted and verified nonce frames refused since this master started.
    pub(crate) fn handshake_counts(&self) -> (u32, u32) {
        (self.adoptions, self.refused)
    }

    /// The master's nonce of the epoch adopted last and the follower's nonce it answers, if
    /// `slot` is in the wrap the follower's nonce was sent in — the only one in which the
    /// follower can check it (a handshake never outlives its wrap).
    pub(crate) fn master_nonce_for(&self, slot: u32) -> Option<(u64, u64)> {
        let e = self.answering?;
        e.in_wrap_zero(slot).then_some((e.master_nonce, e.nonce))
    }

    /// The master moved on to `slot`: an epoch in force whose 2³² slots are used up (the
    /// slot counter came round to its wrap 0) is retired.
    pub(crate) fn on_slot(&mut self, slot: u32) {
        if let Some(e) = self.current
            && slot == e.base
        {
            self.retire(e.nonce);
            self.current = None;
            self.current_heard = None;
        }
    }

    /// The key and counter a downlink of `slot` is checked with under the epoch in force.
    pub(crate) fn current_check(&self, slot: u32) -> Option<(LinkKey, u64)> {
        self.current.map(|e| (e.key, e.counter(slot)))
    }

    /// The key and counter a downlink of `slot` is checked with under the pending epoch.
    pub(crate) fn pending_check(&self, slot: u32) -> Option<(LinkKey, u64)> {
        self.pending.map(|e| (e.key, e.counter(slot)))
    }

    /// A downlink of `slot` verified under the epoch in force: it is live.
    pub(crate) fn heard(&mut self, slot: u32) {
        self.current_heard = Some(slot);
    }

    /// A downlink of `slot` verified under the pending epoch: its follower is in force under
    /// it (the old epoch's follower has moved on), so it comes into force.
    pub(crate) fn confirm(&mut self, slot: u32) {
        let Some(e) = self.pending.take() else {
            return;
        };
        if let Some(old) = self.current.replace(e) {
            self.retire(old.nonce);
        }
        self.current_heard = Some(slot);
    }

    /// A verified nonce frame of master slot `slot` carrying `nonce` and, from a follower
    /// that was in force under an epoch, its `proof` of it, at `now_us`. Adopting draws the
    /// master's own nonce and derives the epoch key from `link`.
    pub(crate) fn offer(
        &mut self,
        nonce: u64,
        proof: Option<u32>,
        slot: u32,
        link: &LinkKey,
        now_us: u64,
    ) -> NonceVerdict {
        let verdict = self.judge(nonce, proof, slot);
        match verdict {
            NonceVerdict::Adopted => self.adopt(nonce, slot, link, now_us),
            NonceVerdict::Refused => self.refused = self.refused.saturating_add(1),
            NonceVerdict::Repeated => {}
        }
        verdict
    }

    fn judge(&self, nonce: u64, proof: Option<u32>, slot: u32) -> NonceVerdict {
        if slot % WRAP_SLOTS == WRAP_SLOTS - 1 {
            // The last slot of its wrap: no uplink is left to answer in, and the follower
            // draws a new nonce at the wrap.
            return NonceVerdict::Refused;
        }
        if let Some(a) = self.answering
            && a.nonce == nonce
        {
            return if a.in_wrap_zero(slot) {
                NonceVerdict::Repeated
            } else {
                NonceVerdict::Refused
            };
        }
        let used = self.recent.contains(&nonce)
            || [self.current, self.pending]
                .iter()
                .flatten()
                .any(|e| e.nonce == nonce);
        if used {
            return NonceVerdict::Refused;
        }
        // The follower of an epoch this master knows proves it with that epoch's key.
        let proven = proof.is_some_and(|proof| {
            [self.current, self.pending]
                .iter()
                .flatten()
                .any(|e| e.key.rekey_proof(nonce, slot as u8) == proof)
        });
        if proven {
            return NonceVerdict::Adopted;
        }
        // Without a proof: never while the epoch in force is live (its follower flies and
        // sends no nonce), and, once it was heard, at most once in a wrap of the slot
        // counter.
        let Some(heard) = self.current_heard else {
            return NonceVerdict::Adopted;
        };
        let live = slot.wrapping_sub(heard) <= self.live_slots;
        let adopted_lately = self
            .last_adoption
            .is_some_and(|s| s / WRAP_SLOTS == slot / WRAP_SLOTS);
        if live || adopted_lately {
            NonceVerdict::Refused
        } else {
            NonceVerdict::Adopted
        }
    }

    /// A new epoch: in force at once when none is (there is no follower to keep flying),
    /// else pending until its follower is heard under it.
    fn adopt(&mut self, nonce: u64, slot: u32, link: &LinkKey, now_us: u64) {
        let master_nonce = self.nonces.draw(now_us);
        let epoch = Adopted {
            nonce,
            master_nonce,
            key: link.epoch_key(nonce, master_nonce),
            base: slot & !(WRAP_SLOTS - 1),
        };
        if self.current.is_none() {
            self.current = Some(epoch);
            self.current_heard = None;
        } else if let Some(old) = self.pending.replace(epoch) {
            self.retire(old.nonce);
        }
        self.answering = Some(epoch);
        self.last_adoption = Some(slot);
        self.adoptions = self.adoptions.saturating_add(1);
    }

    fn retire(&mut self, nonce: u64) {
        if let Some(r) = self.recent.get_mut(self.next_recent) {
            *r = nonce;
        }
        self.next_recent = (self.next_recent + 1) % RECENT_NONCES;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_counter_is_wraps_then_slot_below_2_to_the_32() {
        assert_eq!(counter(0x12_3456, 0x78), 0x1234_5678);
        assert_eq!(counter(WRAPS_LIMIT - 1, 0xFF) >> 32, 0);
        assert_eq!(counter(1, 0), 1 << 8);
    }

    #[test]
    fn nonces_are_never_zero_nor_repeated_back_to_back_and_depend_on_seed_and_time() {
        let mut a = NonceSource::new(7);
        let mut b = NonceSource::new(7);
        let mut c = NonceSource::new(8);
        let xs: Vec<u64> = (0..1000).map(|_| a.draw(5)).collect();
        assert!(xs.iter().all(|&n| n != 0));
        assert!(xs.windows(2).all(|w| w[0] != w[1]));
        assert!(xs.iter().any(|&n| n >> 32 != 0), "64 bits, not 32");
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
        assert_eq!(e.counter(255), Some(counter(0, 255)));
        e.advance(0, &mut nonces, 0);
        assert_eq!(e.counter(0), Some(counter(1, 0)));
        // A handshake never leaves its wrap: a new nonce at the wrap.
        let mut h = FollowerEpoch::Handshake { nonce: 9 };
        assert_eq!(h.counter(3), None, "nothing is checked under the link key");
        h.advance(0, &mut nonces, 0);
        assert!(matches!(h, FollowerEpoch::Handshake { nonce } if nonce != 9));
        // The wraps used up: a new handshake, never a repeated counter.
        let mut e = in_force(WRAPS_LIMIT - 1);
        e.advance(0, &mut nonces, 0);
        assert!(matches!(e, FollowerEpoch::Handshake { nonce } if nonce != 9));
    }

    /// A master at 1:4 whose epochs stay live for 62 slots (F250's 250 ms).
    fn master() -> MasterEpoch {
        MasterEpoch::new(1, 62)
    }

    fn link() -> LinkKey {
        LinkKey::from_bytes([7; 16])
    }

    /// A master with epoch 5 (adopted in slot 259) in force, heard in 263.
    fn flying() -> MasterEpoch {
        let mut m = master();
        assert_eq!(m.offer(5, None, 259, &link(), 0), NonceVerdict::Adopted);
        m.heard(263);
        m
    }

    #[test]
    fn the_first_epoch_is_in_force_at_once_and_answered_in_its_wrap() {
        let mut m = master();
        assert_eq!(m.counter(300), None);
        assert_eq!(m.master_nonce_for(300), None);
        // Nonce sent in slot 259 (wrap starting at 256).
        assert_eq!(m.offer(5, None, 259, &link(), 0), NonceVerdict::Adopted);
        let (n, master_nonce) = m.nonces().expect("in force");
        assert_eq!(n, 5);
        assert_eq!(m.key(), Some(&link().epoch_key(5, master_nonce)));
        assert_eq!(m.master_nonce_for(260), Some((master_nonce, 5)));
        assert_eq!(m.master_nonce_for(512), None, "only in the nonce's wrap");
        assert_eq!(m.offer(5, None, 263, &link(), 0), NonceVerdict::Repeated);
        assert_eq!(
            m.offer(5, None, 259 + 256, &link(), 0),
            NonceVerdict::Refused
        );
        assert_eq!(m.counter(260), Some(counter(0, 4)));
        assert_eq!(m.counter(512), Some(counter(1, 0)));
        assert_eq!(m.handshake_counts(), (1, 1));
    }

    #[test]
    fn a_live_epoch_is_never_retired_by_a_nonce_without_its_proof() {
        let mut m = flying();
        let in_force = m.nonces();
        let current = m.current.expect("in force");
        assert_eq!(
            m.current_check(267),
            Some((current.key, current.counter(267)))
        );
        m.heard(267);
        // A replayed nonce frame (no proof, or a proof of another epoch) is refused for the
        // failsafe period, and nothing changes.
        for slot in [271, 300, 267 + 62] {
            assert_eq!(m.offer(6, None, slot, &link(), 0), NonceVerdict::Refused);
            assert_eq!(
                m.offer(6, Some(1234), slot, &link(), 0),
                NonceVerdict::Refused
            );
        }
        assert_eq!(m.nonces(), in_force);
        assert_eq!(m.pending_nonces(), None);
        // The follower of the epoch in force resynced: its proof takes its new nonce at once,
        // pending until that follower is heard under it.
        let proof = current.key.rekey_proof(7, 275u32 as u8);
        assert_eq!(
            m.offer(7, Some(proof), 275, &link(), 0),
            NonceVerdict::Adopted
        );
        assert_eq!(m.nonces(), in_force, "still in force until confirmed");
        assert_eq!(m.pending_nonces().map(|n| n.0), Some(7));
        assert_eq!(m.master_nonce_for(276).map(|n| n.1), Some(7));
        assert!(m.pending_check(279).is_some());
        m.confirm(279);
        assert_eq!(m.nonces().map(|n| n.0), Some(7));
        assert_eq!(m.pending_nonces(), None);
        // 5 was used: a replay of its handshake is refused, even once quiet.
        assert_eq!(m.offer(5, None, 2000, &link(), 0), NonceVerdict::Refused);
    }

    #[test]
    fn a_quiet_epoch_takes_at_most_one_unproven_nonce_per_wrap_and_keeps_flying() {
        let mut m = flying();
        let in_force = m.nonces();
        // Quiet since 263 (the downlinks jammed): unproven nonces are taken, one per wrap,
        // and never replace the epoch in force until their follower is heard.
        let mut adopted = Vec::new();
        for k in 0..2000u32 {
            let slot = 400 + 4 * k + 3;
            if m.offer(100 + u64::from(k), None, slot, &link(), 0) == NonceVerdict::Adopted {
                adopted.push(slot);
            }
        }
        assert!(!adopted.is_empty());
        let wraps: Vec<u32> = adopted.iter().map(|s| s / 256).collect();
        assert!(wraps.windows(2).all(|w| w[1] > w[0]), "{adopted:?}");
        assert!(adopted.len() <= 2000 * 4 / 256 + 1, "{}", adopted.len());
        assert_eq!(m.nonces(), in_force, "the epoch in force is kept");
        let (adoptions, refused) = m.handshake_counts();
        assert_eq!(adoptions as usize, 1 + adopted.len());
        assert_eq!(adoptions + refused, 2001, "every nonce frame counted");
    }

    #[test]
    fn an_epoch_never_heard_gives_way_to_the_next_nonce() {
        // A master that has just booted adopts what comes first (a replay, maybe); the real
        // follower's nonce right after is taken as well, pending until it is heard.
        let mut m = master();
        assert_eq!(m.offer(5, None, 3, &link(), 0), NonceVerdict::Adopted);
        assert_eq!(m.offer(6, None, 7, &link(), 0), NonceVerdict::Adopted);
        assert_eq!(m.nonces().map(|n| n.0), Some(5));
        assert_eq!(m.pending_nonces().map(|n| n.0), Some(6));
        assert_eq!(m.master_nonce_for(8).map(|n| n.1), Some(6));
        m.confirm(11);
        assert_eq!(m.nonces().map(|n| n.0), Some(6));
        assert_eq!(
            m.offer(5, None, 15, &link(), 0),
            NonceVerdict::Refused,
            "used"
        );
        // Nothing is taken in the last slot of a wrap: no uplink is left to answer in.
        assert_eq!(m.offer(9, None, 511, &link(), 0), NonceVerdict::Refused);
    }

    /// Spec §12.2: with 32-bit nonces a follower that redraws an earlier nonce (forced
    /// re-handshakes, recordings across days) lets a recorded master nonce frame put it back
    /// into the old epoch; 2¹⁸ draws over 2 000 boots repeat a 32-bit value with probability
    /// 1 − e⁻⁸ (8 repeats expected). The 64-bit nonces repeat none (≈ 2⁻²⁹).
    #[test]
    fn nonces_drawn_across_many_boots_do_not_repeat() {
        let mut seen = std::collections::HashSet::new();
        for boot in 0..2000u64 {
            // A hardware random seed per boot, the lock times of 131 handshakes.
            let mut source = NonceSource::new(boot.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0xB007);
            for draw in 0..131u64 {
                assert!(
                    seen.insert(source.draw(1_000_000 + draw * 4_000)),
                    "boot {boot}"
                );
            }
        }
        assert_eq!(seen.len(), 262_000);
    }
}
