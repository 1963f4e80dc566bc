//! The epoch of the frame counter (spec §12.2) between the two keyed state machines, run
//! in lockstep by hand (no radio) with an attacker on the air between them who records
//! every frame and replays, reorders or drops them.

use super::follower::{DEFAULT_FAILSAFE_US, SyncState};
use super::tests::{SLOT_US, pair, test_key};
use super::*;
use crate::channels::Channels;
use crate::frame::{Frame, SEALED_VERSION, peek_sealed};
use crate::link::auth::TagContext;
use crate::link::radio::LinkRx;
use crate::link::schedule::SlotKind;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Dir {
    Up,
    Down,
}

/// What was sent in one slot: direction, the master's slot counter, the bytes (empty when
/// the end due to send did not).
#[derive(Clone, Debug)]
struct OnAir {
    dir: Dir,
    slot: u32,
    bytes: Vec<u8>,
}

/// The channels the master sends in `slot`: channel 1 names the slot, so a replayed frame
/// that got through would show.
fn channels_of(slot: u32) -> Channels {
    let mut ch = [992; 16];
    ch[0] = 200 + (slot % 1500) as u16;
    ch
}

/// Both ends in lockstep (shared slot starts); each slot's frame goes through `air`, which
/// returns what the receiver hears (`None`: nothing) — the attacker's hand.
struct Link {
    master: Master,
    follower: Follower,
    t: u64,
    keyed: bool,
}

impl Link {
    fn new(keyed: bool, seed: u64) -> Self {
        let (master, follower) = pair();
        let mut link = Self {
            master,
            follower,
            t: 0,
            keyed,
        };
        link.restart_follower(seed);
        link.reboot_master();
        link
    }

    fn reboot_master(&mut self) {
        let (master, _) = pair();
        self.master = if self.keyed {
            master.with_key(test_key(1))
        } else {
            master
        };
    }

    fn restart_follower(&mut self, seed: u64) {
        let (_, follower) = pair();
        self.follower = if self.keyed {
            follower.with_key(test_key(1)).with_nonce_seed(seed)
        } else {
            follower
        };
    }

    fn slot(&mut self, air: &mut impl FnMut(&OnAir) -> Option<Vec<u8>>) {
        let (mut mb, mut fb) = ([0u8; 64], [0u8; 64]);
        let slot = self.master.slot();
        let t = self.t;
        let schedule = *self.master.schedule();
        let packet = |b: &Vec<u8>| LinkRx::Packet {
            len: b.len(),
            rssi_dbm: -70,
        };
        let end = |b: &Vec<u8>| t + u64::from(schedule.packet_end_offset_us(b.len()));
        self.master.set_channels(&channels_of(slot));
        let m = self.master.plan(t, &mut mb);
        let f = self.follower.plan(t, &mut fb);
        match m {
            Step::Transmit { channel, len, .. } => {
                self.master.on_sent();
                let heard = air(&OnAir {
                    dir: Dir::Up,
                    slot,
                    bytes: mb[..len].to_vec(),
                });
                match f {
                    Step::Listen { channel: c, .. } if c == channel => {
                        if let Some(b) = heard {
                            self.follower.on_received(packet(&b), &b, end(&b));
                        }
                    }
                    Step::Listen { .. } => {}
                    Step::Transmit { .. } => self.follower.on_sent(),
                    Step::Idle => self.follower.on_skipped(),
                }
            }
            Step::Listen { channel, .. } => {
                let (sent, same_channel) = match f {
                    Step::Transmit {
                        channel: c, len, ..
                    } => {
                        self.follower.on_sent();
                        (fb[..len].to_vec(), c == channel)
                    }
                    Step::Idle => {
                        self.follower.on_skipped();
                        (Vec::new(), true)
                    }
                    Step::Listen { .. } => (Vec::new(), true),
                };
                let heard = air(&OnAir {
                    dir: Dir::Down,
                    slot,
                    bytes: sent,
                });
                if let Some(b) = heard.filter(|b| same_channel && !b.is_empty()) {
                    self.master.on_received(packet(&b), &b, end(&b));
                }
                self.master.finish_listen();
            }
            Step::Idle => self.master.on_skipped(),
        }
        self.t += SLOT_US;
    }

    fn run(&mut self, slots: u32, air: &mut impl FnMut(&OnAir) -> Option<Vec<u8>>) {
        for _ in 0..slots {
            self.slot(air);
        }
    }

    /// Runs slots until the follower tracks and (keyed) both ends have the same epoch in
    /// force; returns how many it took.
    fn until_tracking(&mut self, air: &mut impl FnMut(&OnAir) -> Option<Vec<u8>>) -> u32 {
        for n in 0..10_000 {
            if self.follower.sync_state() == SyncState::Tracking
                && self.follower.epoch_nonces() == self.master.epoch_nonces()
            {
                return n;
            }
            self.slot(air);
        }
        panic!("never tracking");
    }
}

fn clean(frame: &OnAir) -> Option<Vec<u8>> {
    Some(frame.bytes.clone())
}

const RATIO: u32 = 4;
/// Slots of F250 within which the master counts an epoch it heard as live (250 ms).
const LIVE: u32 = 62;

#[test]
fn keyed_ends_handshake_the_epoch_then_fly_and_carry_telemetry() {
    let mut link = Link::new(true, 1);
    let mut states = Vec::new();
    let mut nonce_frames = 0;
    let mut air = |f: &OnAir| {
        assert!(f.bytes.is_empty() || f.bytes[0] == SEALED_VERSION);
        if f.dir == Dir::Down && matches!(peek_sealed(&f.bytes), Some(Frame::Nonce { .. })) {
            nonce_frames += 1;
        }
        Some(f.bytes.clone())
    };
    while link.follower.sync_state() != SyncState::Tracking {
        states.push(link.follower.sync_state());
        // Nothing of the master's is taken before the epoch is in force.
        assert_eq!(link.follower.updates(), 0);
        assert!(link.follower.in_failsafe());
        link.slot(&mut air);
        assert!(states.len() < 200, "no lock");
    }
    let handshake = states
        .iter()
        .filter(|s| **s == SyncState::Handshake)
        .count();
    assert!(handshake > 0, "went through the handshake");
    // The nonce goes out in the first downlink slot after lock, the master's nonce comes
    // back in the next uplink: the epoch is in force (the master's first one is at once).
    assert!(
        handshake as u32 <= RATIO + 1,
        "{handshake} slots of handshake"
    );
    assert!(nonce_frames >= 1);
    assert!(link.master.has_epoch());
    assert_eq!(link.follower.epoch_nonces(), link.master.epoch_nonces());
    // The master's nonce frame carries no channels: they come with the next uplink.
    assert_eq!(link.follower.updates(), 0);
    link.slot(&mut clean);
    assert!(!link.follower.in_failsafe());
    let slot = link.master.slot() - 1;
    assert_eq!(link.follower.output(), &channels_of(slot));
    assert_eq!(link.master.handshakes(), (1, 0));

    link.follower.downlink_stream.write(b"sealed");
    link.run(2 * RATIO, &mut clean);
    let mut got = [0u8; 16];
    let n = link.master.downlink_stream.read(&mut got);
    assert_eq!(&got[..n], b"sealed");
    assert_eq!(link.master.downlink_lq(), 100);
}

/// Records every uplink; in every third uplink slot the attacker (closer to the follower)
/// replaces the master's frame by the one it recorded 256·k slots earlier (k = 1..4): the
/// same slot number, the same hop channel, a valid tag under the on-air slot alone. None
/// verifies; the legitimate frames between keep flying.
#[test]
fn a_frame_recorded_256_or_256k_slots_earlier_never_verifies() {
    let mut link = Link::new(true, 2);
    let recorded = core::cell::RefCell::new(Vec::<Vec<u8>>::new());
    let rec = |f: &OnAir| {
        let mut r = recorded.borrow_mut();
        if r.len() <= f.slot as usize {
            r.resize(f.slot as usize + 1, Vec::new());
        }
        r[f.slot as usize] = f.bytes.clone();
        Some(f.bytes.clone())
    };
    link.until_tracking(&mut { rec });
    link.run(1100, &mut { rec });
    let (mut replayed, mut flown) = (0, 0);
    for _ in 0..600 {
        let slot = link.master.slot();
        let k = 1 + (slot / 3) % 4;
        let replay =
            slot.is_multiple_of(3) && link.master.schedule().kind(slot) == SlotKind::Uplink;
        let old = recorded.borrow()[(slot - 256 * k) as usize].clone();
        let (updates, rejected) = (link.follower.updates(), link.follower.counters().rejected);
        let tag_failures = link.follower.counters().tag_failures;
        link.slot(&mut |f: &OnAir| {
            rec(f);
            if f.dir == Dir::Up && replay {
                assert_eq!(old[2], f.bytes[2], "same on-air slot");
                Some(old.clone())
            } else {
                Some(f.bytes.clone())
            }
        });
        if replay {
            replayed += 1;
            assert_eq!(
                link.follower.updates(),
                updates,
                "replay of slot {slot} - 256·{k} flown"
            );
            assert_eq!(link.follower.counters().rejected, rejected + 1);
            assert_eq!(
                link.follower.counters().tag_failures,
                tag_failures + 1,
                "every replay counted as a tag failure"
            );
        } else if link.master.schedule().kind(slot) == SlotKind::Uplink {
            flown += 1;
            assert_eq!(link.follower.updates(), updates + 1);
            assert_eq!(link.follower.output(), &channels_of(slot));
        }
    }
    assert!(replayed > 100 && flown > 200, "{replayed} {flown}");
    assert_eq!(link.follower.sync_state(), SyncState::Tracking);
}

/// A frame held back one slot (or one downlink period) and delivered in the next: the
/// counter has moved on, so its tag fails, in both directions.
#[test]
fn reordered_frames_are_rejected() {
    let mut link = Link::new(true, 3);
    link.until_tracking(&mut clean);
    link.run(50, &mut clean);
    let mut held_up: Option<Vec<u8>> = None;
    let mut held_down: Option<Vec<u8>> = None;
    let before = (
        link.follower.counters().rejected,
        link.master.counters().rejected,
    );
    let mut updates = link.follower.updates();
    for _ in 0..64 {
        let slot = link.master.slot();
        link.slot(&mut |f: &OnAir| {
            let held = if f.dir == Dir::Up {
                &mut held_up
            } else {
                &mut held_down
            };
            // Each frame is delivered one frame late: the previous one of its direction.
            held.replace(f.bytes.clone())
        });
        if link.master.schedule().kind(slot) == SlotKind::Uplink {
            assert_eq!(
                link.follower.updates(),
                updates,
                "late uplink of slot {slot} flown"
            );
        }
        updates = link.follower.updates();
    }
    assert!(link.follower.counters().rejected > before.0 + 20);
    assert!(link.master.counters().rejected > before.1 + 10);
    assert!(link.master.downlink_lq() < 100);
}

/// The follower restarts (a new nonce): every frame recorded before, uplinks and the old
/// handshake's nonce downlinks alike, replayed in a slot with the same on-air number, fails;
/// the master refuses the old nonce, so the link keeps flying between the replays.
#[test]
fn frames_recorded_before_a_follower_restart_never_verify_after_it() {
    let mut link = Link::new(true, 4);
    let mut before: Vec<OnAir> = Vec::new();
    let mut rec = |f: &OnAir| {
        if !f.bytes.is_empty() {
            before.push(f.clone());
        }
        Some(f.bytes.clone())
    };
    link.until_tracking(&mut rec);
    link.run(1000, &mut rec);
    let old_nonces: Vec<&OnAir> = before
        .iter()
        .filter(|f| matches!(peek_sealed(&f.bytes), Some(Frame::Nonce { .. })))
        .collect();
    assert!(!old_nonces.is_empty());

    link.restart_follower(5);
    link.until_tracking(&mut clean);
    let master_rejected = link.master.counters().rejected;
    let (mut replayed_up, mut replayed_nonce) = (0, 0);
    for _ in 0..1024 {
        let slot = link.master.slot();
        let uplink = link.master.schedule().kind(slot) == SlotKind::Uplink;
        // The latest recording of this on-air slot and direction, if any.
        let dir = if uplink { Dir::Up } else { Dir::Down };
        let old = before
            .iter()
            .rev()
            .find(|f| f.dir == dir && f.slot % 256 == slot % 256)
            .map(|f| f.bytes.clone());
        let is_nonce = old
            .as_ref()
            .is_some_and(|b| matches!(peek_sealed(b), Some(Frame::Nonce { .. })));
        let old_nonce = old_nonces
            .iter()
            .find(|f| f.slot % 256 == slot % 256)
            .map(|f| f.bytes.clone());
        let replay = if uplink {
            old.filter(|_| slot.is_multiple_of(3))
        } else {
            old_nonce.or(old.filter(|_| is_nonce))
        };
        let updates = link.follower.updates();
        let replaying = replay.is_some();
        link.slot(&mut |f: &OnAir| replay.clone().or(Some(f.bytes.clone())));
        if replaying && uplink {
            replayed_up += 1;
            assert_eq!(link.follower.updates(), updates, "old uplink flown");
        } else if replaying {
            replayed_nonce += 1;
        } else if uplink {
            assert_eq!(link.follower.updates(), updates + 1, "slot {slot}");
        }
    }
    assert!(replayed_up > 200, "{replayed_up}");
    assert!(replayed_nonce >= 1, "{replayed_nonce}");
    assert!(link.master.counters().rejected >= master_rejected + replayed_nonce);
    assert_eq!(link.follower.sync_state(), SyncState::Tracking);
    assert_eq!(link.follower.resyncs(), 0, "never lost the link");
}

/// Slots from a master reboot (at a new phase of the hop sequence) until the follower flies
/// its channels again.
fn recovery_after_master_reboot(keyed: bool) -> u32 {
    let mut link = Link::new(keyed, 6);
    link.until_tracking(&mut clean);
    // The same moment of the old grid for both runs, so both re-acquire alike.
    while link.master.slot() < 400 {
        link.slot(&mut clean);
    }
    link.reboot_master();
    let updates = link.follower.updates();
    for n in 1..10_000 {
        link.slot(&mut clean);
        if link.follower.updates() > updates {
            return n;
        }
    }
    panic!("never recovered");
}

/// A rebooted master has no epoch: the follower's tags stop verifying, it re-acquires after
/// `RESYNC_MISSES` and hands over a new nonce, which the master (no epoch in force) puts in
/// force at once. The handshake adds at most one downlink period (ratio + 1 slots) to what
/// an unkeyed link needs to re-acquire.
#[test]
fn a_rebooted_master_is_back_within_one_downlink_period_of_an_unkeyed_reacquisition() {
    let keyed = recovery_after_master_reboot(true);
    let unkeyed = recovery_after_master_reboot(false);
    println!("master reboot → channels again: keyed {keyed} slots, unkeyed {unkeyed} slots");
    assert!(
        keyed <= unkeyed + RATIO + 1,
        "keyed {keyed}, unkeyed {unkeyed}"
    );
    // Resync (32 missed uplinks = 43 slots at 1:4), at most one dwell (33 slots), the
    // downlink slot and the next uplink.
    assert!(keyed <= 43 + 33 + RATIO + 1, "{keyed}");
    // At F250 that is within the failsafe period plus a dwell and a downlink period.
    let us = u64::from(keyed) * SLOT_US;
    assert!(us <= DEFAULT_FAILSAFE_US + 33 * SLOT_US + u64::from(RATIO + 1) * SLOT_US);
}

/// Both ends rebooted (the master remembers no nonce): the attacker replays the nonce
/// downlink of the previous session in its slot, and the master adopts it. That only
/// delays: the follower takes nothing under that epoch, its own nonce follows in the next
/// downlink slot and is adopted (the old epoch was never heard), and the link flies.
#[test]
fn a_replayed_nonce_only_delays_the_handshake() {
    let mut link = Link::new(true, 7);
    let mut old_nonce: Option<OnAir> = None;
    link.until_tracking(&mut |f: &OnAir| {
        if matches!(peek_sealed(&f.bytes), Some(Frame::Nonce { .. })) {
            old_nonce = Some(f.clone());
        }
        Some(f.bytes.clone())
    });
    let old = old_nonce.expect("a nonce frame");
    link.run(100, &mut clean);

    link.reboot_master();
    link.restart_follower(8);
    let mut replayed_at = None;
    let mut slots = 0;
    while link.follower.sync_state() != SyncState::Tracking {
        let slot = link.master.slot();
        let replay = slot % 256 == old.slot % 256 && replayed_at.is_none();
        if replay {
            replayed_at = Some(slots);
        }
        link.slot(&mut |f: &OnAir| {
            if f.dir == Dir::Down && replay {
                Some(old.bytes.clone())
            } else {
                Some(f.bytes.clone())
            }
        });
        if replay {
            assert!(
                link.master.has_epoch(),
                "the fresh master adopted the replayed nonce"
            );
        }
        if replayed_at.is_some() && link.follower.sync_state() != SyncState::Tracking {
            assert_eq!(link.follower.updates(), 0, "flown under the replayed epoch");
        }
        slots += 1;
        assert!(slots < 1000);
    }
    let replayed_at = replayed_at.expect("replayed");
    let delay = slots - replayed_at;
    println!("replayed nonce at slot {replayed_at}; link in force {delay} slots later");
    assert!(delay <= 2 * RATIO + 1, "{delay}");
    link.run(20, &mut clean);
    assert!(link.follower.updates() > 10);
    assert!(!link.follower.in_failsafe());
}

#[test]
fn unkeyed_ends_have_no_handshake_and_take_the_first_uplink() {
    let mut link = Link::new(false, 0);
    let mut states = Vec::new();
    while link.follower.updates() == 0 {
        states.push(link.follower.sync_state());
        link.slot(&mut clean);
    }
    assert!(!states.contains(&SyncState::Handshake));
    assert_eq!(link.follower.sync_state(), SyncState::Tracking);
    assert!(!link.master.has_epoch());
}

/// The read-only counters the fuzz harnesses seal under (`Master::frame_counter`,
/// `Follower::frame_counter`) are the ones each end really uses: both ends name the same
/// counter for every slot once the epoch is in force, across a wrap of the slot counter; a
/// frame sealed under the follower's counter is what it accepts, under any other it is not.
#[test]
fn both_ends_report_the_counter_they_tag_and_check_under() {
    let mut link = Link::new(true, 5);
    assert_eq!(
        link.follower.frame_counter(),
        None,
        "acquiring: nothing verifies"
    );
    assert_eq!(link.master.frame_counter(), None, "no epoch yet");
    link.until_tracking(&mut clean);
    for _ in 0..300 {
        let master = link.master.frame_counter().expect("in force");
        let (follower_slot, _) = link.follower.tracked_slot().expect("tracking");
        assert_eq!(follower_slot, link.master.slot() as u8);
        assert_eq!(link.follower.frame_counter(), Some(master));
        assert_eq!(master, frame_counter(master >> 8, master as u8));
        link.slot(&mut clean);
    }
    let wraps = link.master.frame_counter().expect("in force") >> 8;
    assert!(wraps >= 1, "ran past a wrap of the slot counter");

    // Forge an uplink of the tracked slot with the key, under the reported counter and
    // under its neighbours: only the first is taken.
    while link.master.schedule().kind(link.master.slot()) != SlotKind::Uplink {
        link.slot(&mut clean);
    }
    let take = |counter: u64, link: &mut Link| {
        let (slot, _) = link.follower.tracked_slot().expect("tracking");
        let packed = [0u8; 22];
        let up = crate::frame::Uplink {
            slot,
            stream: crate::frame::StreamHeader { seq: 0, ack: 0 },
            report: None,
            save_failsafe: false,
            input_lost: false,
            format: crate::channels::ChannelFormat::Full16,
            packed_channels: &packed,
            data: &[],
        };
        let mut buf = [0u8; 64];
        let (n, m) = link.follower.epoch_nonces().expect("in force");
        let epoch_key = test_key(1).epoch_key(n, m);
        let context = TagContext::Counter(counter);
        let len =
            crate::frame::seal(&Frame::Uplink(up), &epoch_key, &context, &mut buf).expect("fits");
        let before = link.follower.updates();
        link.follower.on_received(
            LinkRx::Packet { len, rssi_dbm: -70 },
            &buf[..len],
            link.t + 1_000,
        );
        link.follower.updates() != before
    };
    let expected = link.follower.frame_counter().expect("in force");
    for wrong in [expected ^ 1 << 8, expected ^ 1 << 31, expected + 256] {
        assert!(!take(wrong, &mut link), "accepted under {wrong:#x}");
    }
    assert!(take(expected, &mut link), "refused under its own counter");
}

/// One keyed session as an eavesdropper recorded it: the follower's nonce frame that the
/// master adopted, and every downlink of that epoch with its master slot counted from the
/// epoch's wrap 0 (where a master that adopts the nonce again would tag it).
struct Recording {
    nonce: OnAir,
    downlinks: Vec<(u32, Vec<u8>)>,
    master_nonces: Vec<OnAir>,
    epoch: Option<(u64, u64)>,
}

/// The nonce a follower's nonce frame carries.
fn nonce_in(bytes: &[u8]) -> u64 {
    match peek_sealed(bytes) {
        Some(Frame::Nonce { nonce, .. }) => nonce,
        other => panic!("no nonce frame: {other:?}"),
    }
}

fn is_nonce(bytes: &[u8]) -> bool {
    matches!(peek_sealed(bytes), Some(Frame::Nonce { .. }))
}

fn is_master_nonce(bytes: &[u8]) -> bool {
    matches!(peek_sealed(bytes), Some(Frame::MasterNonce { .. }))
}

fn record_first_epoch(link: &mut Link) -> Recording {
    let mut nonces = Vec::new();
    let mut master_nonces = Vec::new();
    link.until_tracking(&mut |f: &OnAir| {
        if f.dir == Dir::Down && is_nonce(&f.bytes) {
            nonces.push(f.clone());
        }
        if f.dir == Dir::Up && is_master_nonce(&f.bytes) {
            master_nonces.push(f.clone());
        }
        Some(f.bytes.clone())
    });
    let epoch = link.master.epoch_nonces().expect("in force").0;
    let nonce = nonces
        .into_iter()
        .rev()
        .find(|f| nonce_in(&f.bytes) == epoch)
        .expect("the adopted nonce frame");
    let base = nonce.slot & !0xFF;
    let mut downlinks = Vec::new();
    link.run(700, &mut |f: &OnAir| {
        if f.dir == Dir::Down && !f.bytes.is_empty() && !is_nonce(&f.bytes) {
            downlinks.push((f.slot - base, f.bytes.clone()));
        }
        Some(f.bytes.clone())
    });
    assert!(downlinks.len() > 150, "{}", downlinks.len());
    Recording {
        nonce,
        downlinks,
        master_nonces,
        epoch: link.master.epoch_nonces(),
    }
}

/// The attacker jams the follower's downlinks for more than a wrap of the slot counter (so
/// the master no longer hears its epoch and may adopt an unproven nonce), replays the
/// recorded nonce frame in a slot with the same on-air number, and then, in every downlink
/// slot, the recorded downlink of the same position in its epoch. Returns (whether the
/// master adopted the old nonce, how many of the old downlinks it took).
fn replay_old_epoch(link: &mut Link, rec: &Recording) -> (bool, usize) {
    let old = nonce_in(&rec.nonce.bytes);
    let mut target = link.master.slot() + 256 + LIVE;
    while target % 256 != rec.nonce.slot % 256 {
        target += 1;
    }
    while link.master.slot() < target {
        link.slot(&mut |f: &OnAir| (f.dir == Dir::Up).then(|| f.bytes.clone()));
    }
    link.slot(&mut |f: &OnAir| match f.dir {
        Dir::Down => Some(rec.nonce.bytes.clone()),
        Dir::Up => Some(f.bytes.clone()),
    });
    let adopted = [
        link.master.epoch_nonces(),
        link.master.pending_epoch_nonces(),
    ]
    .iter()
    .flatten()
    .any(|(n, _)| *n == old);
    let base = target & !0xFF;
    let mut taken = 0;
    for _ in 0..700 {
        let slot = link.master.slot();
        let recorded = rec
            .downlinks
            .iter()
            .find(|(at, _)| *at == slot - base)
            .map(|(_, b)| b.clone());
        let received = link.master.counters().received;
        let available = link.master.downlink_stream.available();
        link.slot(&mut |f: &OnAir| match f.dir {
            Dir::Down => recorded.clone(),
            Dir::Up => Some(f.bytes.clone()),
        });
        if recorded.is_some() && link.master.counters().received > received {
            taken += 1;
        } else {
            assert_eq!(
                link.master.downlink_stream.available(),
                available,
                "stream from a refused frame"
            );
        }
    }
    (adopted, taken)
}

/// The master remembered only its last 8 follower nonces (spec §12.7): after nine
/// re-acquisitions a recorded nonce frame was adopted again with its old counters, and the
/// downlinks recorded in that epoch verified again. With the master's own nonce in the epoch
/// the old nonce is still adopted (nothing remembers it), but under a fresh epoch key: none
/// of the old downlinks verifies. (Fails on the code before the master's nonce: 170+ taken.)
#[test]
fn a_nonce_replayed_after_nine_reacquisitions_never_makes_an_earlier_downlink_verify() {
    let mut link = Link::new(true, 11);
    let rec = record_first_epoch(&mut link);
    let mut epochs = vec![link.master.epoch_nonces().expect("in force").0];
    for i in 0..9 {
        link.restart_follower(100 + i);
        link.until_tracking(&mut clean);
        link.run(50, &mut clean);
        epochs.push(link.master.epoch_nonces().expect("in force").0);
    }
    epochs.dedup();
    assert_eq!(epochs.len(), 10, "nine re-acquisitions, nine new epochs");
    let (adopted, taken) = replay_old_epoch(&mut link, &rec);
    assert!(
        adopted,
        "the attack reached the master: the old nonce was adopted"
    );
    assert_eq!(taken, 0, "old downlinks verified again");
}

/// The same replay to a master that has just rebooted (it remembers no nonce at all).
#[test]
fn a_nonce_replayed_to_a_rebooted_master_never_makes_an_earlier_downlink_verify() {
    let mut link = Link::new(true, 12);
    let rec = record_first_epoch(&mut link);
    link.reboot_master();
    let (adopted, taken) = replay_old_epoch(&mut link, &rec);
    assert!(
        adopted,
        "the attack reached the master: the old nonce was adopted"
    );
    assert_eq!(taken, 0, "old downlinks verified again");
}

/// A restarted follower (new nonce) is in its handshake; the attacker jams every master
/// nonce frame of the new handshake and replays the one recorded in the first session in
/// its slot: it never verifies (it is tagged under the old follower nonce), so the follower
/// never goes in force under the old epoch and takes nothing; once the jamming stops it is
/// in force under the new epoch, the master's.
#[test]
fn a_replayed_master_nonce_never_puts_a_follower_in_force_under_an_old_epoch() {
    let mut link = Link::new(true, 13);
    let rec = record_first_epoch(&mut link);
    assert!(!rec.master_nonces.is_empty());
    link.restart_follower(14);
    let mut delivered = 0;
    for _ in 0..1024 {
        let slot = link.master.slot();
        let old = rec
            .master_nonces
            .iter()
            .find(|f| f.slot % 256 == slot % 256)
            .map(|f| f.bytes.clone());
        let handshaking = link.follower.sync_state() == SyncState::Handshake;
        let mut replayed = false;
        link.slot(&mut |f: &OnAir| {
            if f.dir == Dir::Up && old.is_some() {
                replayed = true;
                return old.clone();
            }
            if f.dir == Dir::Up && is_master_nonce(&f.bytes) {
                return None;
            }
            Some(f.bytes.clone())
        });
        if replayed && handshaking {
            delivered += 1;
        }
        assert_ne!(link.follower.sync_state(), SyncState::Tracking);
        assert_eq!(link.follower.epoch_nonces(), None);
        assert_eq!(link.follower.updates(), 0, "channels before the epoch");
        assert_eq!(link.follower.uplink_stream.available(), 0);
        assert!(link.follower.in_failsafe());
    }
    assert!(delivered >= 1, "{delivered}");
    link.until_tracking(&mut clean);
    link.run(RATIO + 1, &mut clean);
    assert_eq!(link.follower.epoch_nonces(), link.master.epoch_nonces());
    assert_ne!(link.follower.epoch_nonces(), rec.epoch);
    link.run(8, &mut clean);
    assert!(link.follower.updates() > 0);
}

/// Slots from a follower restart (at a new phase of its clock) until it flies the master's
/// channels again.
fn recovery_after_follower_restart(keyed: bool) -> u32 {
    let mut link = Link::new(keyed, 15);
    link.until_tracking(&mut clean);
    while link.master.slot() < 400 {
        link.slot(&mut clean);
    }
    link.restart_follower(16);
    for n in 1..10_000 {
        link.slot(&mut clean);
        if link.follower.updates() > 0 {
            return n;
        }
    }
    panic!("never recovered");
}

/// A restarted follower (no epoch to prove) acquires like an unkeyed one and hands over its
/// nonce; the master, which heard the old epoch in the slots before the restart, takes a
/// nonce without proof only once that epoch has been quiet for the failsafe period (a
/// replayed nonce frame looks the same), then puts it in force when the follower is heard
/// under it: a downlink period for the handshake and one for the confirmation after the
/// later of the two.
#[test]
fn a_restarted_follower_is_back_a_failsafe_period_after_its_last_downlink() {
    let keyed = recovery_after_follower_restart(true);
    let unkeyed = recovery_after_follower_restart(false);
    println!("follower restart → channels again: keyed {keyed} slots, unkeyed {unkeyed} slots");
    assert!(
        keyed <= unkeyed.max(LIVE) + 2 * RATIO + 2,
        "keyed {keyed}, unkeyed {unkeyed}"
    );
}

/// During the handshake the follower checks uplinks with the link key in the master-nonce
/// context of its nonce, which only the master's nonce frame is sent under: a channel
/// uplink sealed there (only a holder of the key could make one) is still not taken —
/// channels come only under the epoch key. (Found by `air_follower_keyed`.)
#[test]
fn in_the_handshake_only_the_master_nonce_is_taken_under_the_handshake_counter() {
    let mut link = Link::new(true, 17);
    while link.follower.sync_state() != SyncState::Handshake {
        link.slot(&mut clean);
    }
    while link.master.schedule().kind(link.master.slot()) != SlotKind::Uplink
        || link.follower.sync_state() != SyncState::Handshake
    {
        link.slot(&mut clean);
    }
    let (slot, _) = link.follower.tracked_slot().expect("on the grid");
    let follower_nonce = link.follower.handshake_nonce().expect("in the handshake");
    assert_eq!(link.follower.frame_counter(), None);
    let packed = [0u8; 22];
    let up = crate::frame::Uplink {
        slot,
        stream: crate::frame::StreamHeader { seq: 0, ack: 0 },
        report: None,
        save_failsafe: true,
        input_lost: false,
        format: crate::channels::ChannelFormat::Full16,
        packed_channels: &packed,
        data: b"inject",
    };
    let mut buf = [0u8; 64];
    let context = TagContext::MasterNonce { follower_nonce };
    let len = crate::frame::seal(&Frame::Uplink(up), &test_key(1), &context, &mut buf).unwrap();
    let failsafe = *link.follower.failsafe_values();
    link.follower.on_received(
        LinkRx::Packet { len, rssi_dbm: -70 },
        &buf[..len],
        link.t + 1_000,
    );
    assert_eq!(link.follower.updates(), 0);
    assert_eq!(link.follower.failsafe_values(), &failsafe);
    assert_eq!(link.follower.uplink_stream.available(), 0);
    assert_eq!(link.follower.counters().received, 0);
    assert_ne!(link.follower.sync_state(), SyncState::Tracking);
}

/// Issue 30, finding 3: a nonce frame recorded in an earlier power cycle of the flight side,
/// replayed in the downlink slot after one the attacker jammed at the module, was adopted
/// (the epoch was "live" only if heard in the previous downlink slot): every uplink then
/// failed at the follower until it re-acquired. The epoch in force now stays: the frame is
/// refused while the epoch is live, the follower flies every uplink, nothing resyncs.
#[test]
fn a_replayed_nonce_frame_never_tears_down_a_live_link() {
    let mut link = Link::new(true, 21);
    let mut old_nonces: Vec<OnAir> = Vec::new();
    link.until_tracking(&mut |f: &OnAir| {
        if f.dir == Dir::Down && matches!(peek_sealed(&f.bytes), Some(Frame::Nonce { .. })) {
            old_nonces.push(f.clone());
        }
        Some(f.bytes.clone())
    });
    link.run(300, &mut clean);
    // Both ends are power-cycled: a new follower, a master that remembers no nonce.
    link.reboot_master();
    link.restart_follower(22);
    link.until_tracking(&mut clean);
    link.run(300, &mut clean);
    let epoch = link.master.epoch_nonces();
    let resyncs = link.follower.resyncs();
    let mut attacks = 0;
    for _ in 0..4 * 256 {
        let slot = link.master.slot();
        let replay_at = slot + RATIO;
        let old = old_nonces
            .iter()
            .find(|f| f.slot % 256 == replay_at % 256)
            .map(|f| f.bytes.clone());
        if link.master.schedule().kind(slot) == SlotKind::Downlink && old.is_some() {
            // Jam this downlink at the module, replay the old nonce frame in the next one.
            attacks += 1;
            link.slot(&mut |f: &OnAir| (f.dir == Dir::Up).then(|| f.bytes.clone()));
            for _ in 0..RATIO {
                let slot = link.master.slot();
                let updates = link.follower.updates();
                let uplink = link.master.schedule().kind(slot) == SlotKind::Uplink;
                link.slot(&mut |f: &OnAir| match f.dir {
                    Dir::Down => old.clone(),
                    Dir::Up => Some(f.bytes.clone()),
                });
                if uplink {
                    assert_eq!(link.follower.updates(), updates + 1, "slot {slot} lost");
                }
            }
        } else {
            let updates = link.follower.updates();
            let uplink = link.master.schedule().kind(slot) == SlotKind::Uplink;
            link.slot(&mut clean);
            if uplink {
                assert_eq!(link.follower.updates(), updates + 1, "slot {slot} lost");
            }
        }
    }
    assert!(attacks >= 4, "{attacks}");
    assert_eq!(
        link.master.epoch_nonces(),
        epoch,
        "the epoch in force stays"
    );
    assert_eq!(link.follower.resyncs(), resyncs, "the link never dropped");
    assert!(
        link.master.handshakes().1 >= attacks,
        "every replay refused and counted"
    );
}

/// A follower that lost the master long enough to re-acquire (32 uplinks jammed at the
/// flight side) proves its previous epoch in its new nonce frame: the master, which heard
/// its downlinks until then (the epoch is live), takes it at once.
#[test]
fn a_resynced_follower_proves_its_epoch_and_is_taken_at_once() {
    let mut link = Link::new(true, 23);
    link.until_tracking(&mut clean);
    link.run(300, &mut clean);
    let resyncs = link.follower.resyncs();
    while link.follower.resyncs() == resyncs {
        link.slot(&mut |f: &OnAir| (f.dir == Dir::Down).then(|| f.bytes.clone()));
    }
    let proven = core::cell::Cell::new(false);
    let back = link.until_tracking(&mut |f: &OnAir| {
        if let Some(Frame::Nonce { proof: Some(_), .. }) = peek_sealed(&f.bytes) {
            proven.set(true);
        }
        Some(f.bytes.clone())
    });
    assert!(proven.get(), "the nonce frame carried the proof");
    // A dwell to re-acquire, then a downlink period each for the handshake and for the
    // master to hear the follower under the new epoch — well inside the live period.
    assert!(back <= 33 + 2 * RATIO + 2, "{back} slots");
    assert_eq!(link.master.handshakes(), (2, 0));
    let updates = link.follower.updates();
    link.run(RATIO, &mut clean);
    assert!(link.follower.updates() > updates);
}

/// Issue 30, finding 7: wrong tags were silent (only `rejected` rose, as for any noise) and
/// one accepted uplink with the save-failsafe flag rewrote the failsafe values. Tag failures
/// are now counted at both ends; a lucky forgery — here a frame sealed with the key in place
/// of the master's — flies its one update but does not rewrite the failsafe values.
#[test]
fn tag_failures_are_counted_and_one_frame_cannot_rewrite_the_failsafe_values() {
    let mut link = Link::new(true, 24);
    link.until_tracking(&mut clean);
    link.run(40, &mut clean);
    while link.master.schedule().kind(link.master.slot()) != SlotKind::Uplink {
        link.slot(&mut clean);
    }
    let (slot, _) = link.follower.tracked_slot().expect("tracking");
    let mut evil = [992u16; 16];
    evil[2] = 1811;
    let mut packed = [0u8; 22];
    crate::channels::pack(&evil, crate::channels::ChannelFormat::Full16, &mut packed);
    let up = crate::frame::Uplink {
        slot,
        stream: crate::frame::StreamHeader { seq: 0, ack: 0 },
        report: None,
        save_failsafe: true,
        input_lost: false,
        format: crate::channels::ChannelFormat::Full16,
        packed_channels: &packed,
        data: &[],
    };
    let mut forged = [0u8; 64];
    let wrong = test_key(9);
    let n = crate::frame::seal(
        &Frame::Uplink(up),
        &wrong,
        &TagContext::Counter(0),
        &mut forged,
    )
    .unwrap();
    let before = link.follower.counters();
    for k in 0..100_000u64 {
        link.follower.on_received(
            LinkRx::Packet {
                len: n,
                rssi_dbm: -40,
            },
            &forged[..n],
            link.t + 100 + k % 500,
        );
    }
    let after = link.follower.counters();
    assert_eq!(after.tag_failures, before.tag_failures + 100_000);
    assert_eq!(after.received, before.received);
    // The lucky one: sealed with the epoch key under the right counter.
    let (nonce, master_nonce) = link.follower.epoch_nonces().expect("in force");
    let epoch_key = test_key(1).epoch_key(nonce, master_nonce);
    let counter = link.follower.frame_counter().expect("in force");
    let n = crate::frame::seal(
        &Frame::Uplink(up),
        &epoch_key,
        &TagContext::Counter(counter),
        &mut forged,
    )
    .unwrap();
    let failsafe = *link.follower.failsafe_values();
    link.slot(&mut |f: &OnAir| match f.dir {
        Dir::Up => Some(forged[..n].to_vec()),
        Dir::Down => Some(f.bytes.clone()),
    });
    assert_eq!(link.follower.output()[2], 1811, "the one update flies");
    assert_eq!(
        link.follower.failsafe_values(),
        &failsafe,
        "one frame rewrote the failsafe values"
    );
    // The master's own uplinks follow: no flag, and the run of flags is over.
    link.run(2 * RATIO, &mut clean);
    assert_eq!(link.follower.failsafe_values(), &failsafe);
    assert_ne!(link.follower.output()[2], 1811);
    // At the master: a forged downlink of its slot is a tag failure too.
    while link.master.schedule().kind(link.master.slot()) != SlotKind::Downlink {
        link.slot(&mut clean);
    }
    let down = Frame::Downlink(crate::frame::Downlink {
        slot: link.master.slot() as u8,
        stream: crate::frame::StreamHeader { seq: 0, ack: 0 },
        report: None,
        data: b"set",
    });
    let n = crate::frame::seal(&down, &wrong, &TagContext::Counter(0), &mut forged).unwrap();
    let master_failures = link.master.counters().tag_failures;
    link.slot(&mut |f: &OnAir| match f.dir {
        Dir::Down => Some(forged[..n].to_vec()),
        Dir::Up => Some(f.bytes.clone()),
    });
    assert_eq!(link.master.counters().tag_failures, master_failures + 1);
}
