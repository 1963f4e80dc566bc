//! Sealed uplinks into a keyed follower (`Follower::with_key`, spec §12.2), through
//! acquisition, the epoch handshake (timing-only lock, nonce frames in its downlink slots) and
//! tracking under the epoch in force. Most frames are tagged in the context the follower
//! checks — the epoch key under the counter it reports (`Follower::frame_counter`), or in the
//! handshake the link key under its nonce (`Follower::handshake_nonce`) — so channels,
//! flags, failsafe values and the stream are reached; the rest in other contexts, untagged,
//! raw, or replays of earlier frames, to fuzz the rejection paths. Interleaved with
//! planning, sending, runs of skipped slots (into resync), clean stretches of link (past
//! wraps of the slot counter) and stream use.
//!
//! Invariants: a frame is taken (channels, flags, failsafe values, stream, report) only if it
//! verifies as an uplink of the tracked slot with the epoch key under the counter reported
//! before it arrived — never while acquiring or handshaking, never in another context; the
//! handshake ends only on a master nonce of the tracked slot verified with the link key
//! under the follower's nonce, which carries nothing else, and the epoch is then that of
//! both nonces; no (epoch, counter) is taken twice (no replay); the failsafe values change
//! only on the second of two uplinks in a row that ask for it (one accepted frame alone never
//! rewrites them); no channels before the handshake completes; an unverified frame never
//! moves the grid of an epoch in force nor ends a handshake; the counter rises by exactly one
//! per slot within an epoch, and a true uplink of the tracked slot under the reported counter
//! is always taken; every planned downlink fits the mode's frame and verifies: in the
//! handshake a nonce frame of the tracked slot with the follower's nonce (link key) and, after
//! a resync from an epoch in force, that epoch's proof; after it a downlink of the tracked
//! slot under the epoch key and reported counter; no two sent under one epoch share a
//! counter; outputs 11-bit, LQ a percentage.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::air::{self, Replays, Sealing};
use taulink_fuzz::{Input, link_key, seal_tagged};
use telemetry::channels::FailsafeValues;
use telemetry::frame::{Frame, Received, SEALED_VERSION, StreamHeader, Uplink, open, seal};
use telemetry::link::auth::TagContext;
use telemetry::link::core::follower::{SAVE_FAILSAFE_FRAMES, SyncState};
use telemetry::link::core::{Follower, Step, frame_counter};
use telemetry::link::{HOP_CHANNELS, LinkKey, LinkParams, LinkRx, SlotKind};

/// What the harness knows of the follower's past.
#[derive(Default)]
struct Seen {
    /// (epoch, counter) of every uplink taken.
    taken: Vec<((u64, u64), u64)>,
    /// (epoch, counter) of the last downlink sent.
    last_sent: Option<((u64, u64), u64)>,
    /// The last epoch seen in force (a resynced follower proves it).
    in_force: Option<(u64, u64)>,
    /// Save-failsafe uplinks taken in a row.
    save_flags: u8,
}

impl Seen {
    fn observe(&mut self, follower: &Follower) {
        if let Some(epoch) = follower.epoch_nonces() {
            self.in_force = Some(epoch);
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let key = link_key(&mut input);
    let params = air::params(&mut input, true);
    let failsafe_us = u64::from(input.u16()) * 16;
    let mut follower = Follower::new(params, FailsafeValues::default(), failsafe_us)
        .with_key(key)
        .with_nonce_seed(u64::from(input.u32()));
    let mut now = 0u64;
    let mut buf = [0u8; 64];
    let mut heard = Replays::default();
    let mut seen = Seen::default();
    while !input.is_empty() {
        now = now.saturating_add(u64::from(input.u16()));
        match input.u8() % 9 {
            0..=2 => {
                let frame = match input.u8() % 8 {
                    0 if follower.sync_state() == SyncState::Handshake => {
                        master_nonce(&mut input, &follower, &key)
                    }
                    0..=3 => uplink(&mut input, &params, &follower, &key),
                    4 => {
                        let context = follower
                            .frame_counter()
                            .map_or_else(|| air::any_context(&mut input), TagContext::Counter);
                        seal_tagged(input.chunk(40), &epoch_key(&key, &follower), &context)
                    }
                    5 if !heard.is_empty() => heard.pick(&mut input),
                    6 => {
                        let context = air::any_context(&mut input);
                        seal_tagged(input.chunk(40), &key, &context)
                    }
                    _ => input.chunk(40).to_vec(),
                };
                heard.keep(&frame);
                receive(&mut follower, &key, &frame, &mut input, now, &mut seen);
            }
            3 => {
                let outcome = air::nothing(&mut input);
                let (updates, slot) = (follower.updates(), follower.tracked_slot());
                let state = follower.sync_state();
                follower.on_received(outcome, &[], now);
                assert_eq!(follower.updates(), updates);
                if state == SyncState::Tracking {
                    assert_eq!(follower.tracked_slot(), slot);
                }
            }
            4 | 5 => {
                let step = follower.plan(now, &mut buf);
                air::assert_grid(&step);
                match step {
                    Step::Transmit { len, .. } => {
                        let sent = check_downlink(&buf[..len], &params, &follower, &key, &seen);
                        if input.bool() {
                            if let Some(sent) = sent {
                                if let Some((epoch, last)) = seen.last_sent
                                    && epoch == sent.0
                                {
                                    assert!(sent.1 > last, "two downlinks under {:#x}", sent.1);
                                }
                                seen.last_sent = Some(sent);
                            }
                            follower.on_sent();
                        } else {
                            follower.on_skipped();
                        }
                    }
                    step => air::follower_listen_or_idle(&mut follower, step, now),
                }
            }
            6 => {
                // The loop fell behind: a run of skipped slots (past a wrap, or into resync).
                let updates = follower.updates();
                for _ in 0..input.u16() % 600 {
                    let before = follower.frame_counter();
                    let epoch = follower.epoch_nonces();
                    follower.on_skipped();
                    if let (Some(b), Some(a)) = (before, follower.frame_counter())
                        && epoch == follower.epoch_nonces()
                    {
                        assert_eq!(a, b + 1, "the counter moves one per slot");
                    }
                    seen.observe(&follower);
                }
                assert_eq!(follower.updates(), updates);
            }
            7 => clean_run(&mut follower, &key, &params, &mut input, now, &mut seen),
            _ => air::use_follower_streams(&mut input, &mut follower),
        }
        seen.observe(&follower);
        air::assert_follower(&follower);
        if follower.updates() == 0 {
            assert!(
                follower.in_failsafe(),
                "channels before any verified uplink"
            );
        }
        match follower.sync_state() {
            SyncState::Acquiring => {
                assert_eq!(follower.frame_counter(), None);
                assert_eq!(follower.handshake_nonce(), None);
            }
            SyncState::Handshake => {
                assert_eq!(follower.frame_counter(), None);
                assert_ne!(follower.handshake_nonce(), Some(0), "nonces are never 0");
                assert!(follower.handshake_nonce().is_some());
            }
            SyncState::Tracking => {
                let counter = follower.frame_counter().expect("an epoch");
                let (slot, channel) = follower.tracked_slot().expect("on the grid");
                assert_eq!(counter as u8, slot);
                assert!(counter < 1 << 32, "wraps₂₄ ‖ slot₈");
                assert!(usize::from(channel) < HOP_CHANNELS);
            }
        }
    }
});

/// Checks a planned downlink: the handshake's nonce frame (with the proof of the last epoch
/// in force after a resync) or a downlink of the tracked slot under the epoch. Returns the
/// (epoch, counter) of the latter.
fn check_downlink(
    frame: &[u8],
    params: &LinkParams,
    follower: &Follower,
    key: &LinkKey,
    seen: &Seen,
) -> Option<((u64, u64), u64)> {
    assert!(frame.len() <= params.rate.max_frame_bytes());
    assert_eq!(frame.first(), Some(&SEALED_VERSION));
    let (slot, _) = follower.tracked_slot().expect("sends only when tracking");
    if let Some(nonce) = follower.handshake_nonce() {
        let Received::Accepted(Frame::Nonce {
            slot: s,
            nonce: n,
            proof,
        }) = open(frame, key, &TagContext::FollowerNonce)
        else {
            panic!("planned no nonce frame in the handshake");
        };
        assert_eq!((s, n), (slot, nonce));
        let expected = seen
            .in_force
            .map(|(f, m)| key.epoch_key(f, m).rekey_proof(nonce, slot));
        assert_eq!(proof, expected, "the proof is the last epoch's");
        return None;
    }
    let counter = follower.frame_counter().expect("sends only with an epoch");
    let epoch = follower.epoch_nonces().expect("in force");
    let received = open(
        frame,
        &epoch_key(key, follower),
        &TagContext::Counter(counter),
    );
    let Received::Accepted(Frame::Downlink(down)) = received else {
        panic!("planned {received:?} under the epoch");
    };
    assert_eq!(down.slot, slot);
    assert!(down.report.is_some_and(|r| r.lq_percent <= 100));
    Some((epoch, counter))
}

/// Feeds one packet and checks that whatever it changed is explained by a verified uplink.
fn receive(
    follower: &mut Follower,
    key: &LinkKey,
    frame: &[u8],
    input: &mut Input,
    now: u64,
    seen: &mut Seen,
) {
    let expected = follower.frame_counter();
    let tag_key = epoch_key(key, follower);
    let epoch = follower.epoch_nonces();
    let handshake = follower.handshake_nonce();
    let state = follower.sync_state();
    let slot = follower.tracked_slot();
    let (updates, received) = (follower.updates(), follower.counters().received);
    let output = *follower.output();
    let failsafe = *follower.failsafe_values();
    let available = follower.uplink_stream.available();
    let remote = follower.remote_report();
    follower.on_received(air::packet(input, frame), frame, now);

    if follower.counters().received == received {
        assert_eq!(follower.updates(), updates, "channels from a refused frame");
        assert_eq!(follower.failsafe_values(), &failsafe);
        assert_eq!(follower.uplink_stream.available(), available);
        assert_eq!(follower.remote_report(), remote);
        if !follower.in_failsafe() {
            assert_eq!(
                follower.output(),
                &output,
                "outputs moved without an update"
            );
        }
        if state != SyncState::Tracking {
            assert_ne!(
                follower.sync_state(),
                SyncState::Tracking,
                "handshake ended unverified"
            );
        } else {
            assert_eq!(
                follower.tracked_slot(),
                slot,
                "an unverified frame moved the grid"
            );
            assert_eq!(follower.frame_counter(), expected);
        }
        return;
    }

    let (slot, _) = slot.expect("a frame taken while acquiring");
    if state == SyncState::Handshake {
        // Only the master's nonce ends a handshake, and it carries nothing else.
        let follower_nonce = handshake.expect("a handshake nonce");
        let Received::Accepted(Frame::MasterNonce { slot: s, nonce: m }) =
            open(frame, key, &TagContext::MasterNonce { follower_nonce })
        else {
            panic!("taken in the handshake but no master nonce");
        };
        assert_eq!(s, slot);
        assert_eq!(follower.sync_state(), SyncState::Tracking);
        assert_eq!(follower.epoch_nonces(), Some((follower_nonce, m)));
        assert_eq!(follower.updates(), updates);
        assert_eq!(follower.failsafe_values(), &failsafe);
        assert_eq!(follower.uplink_stream.available(), available);
        assert_eq!(follower.remote_report(), remote);
        assert_eq!(follower.frame_counter(), Some(frame_counter(0, slot) + 1));
        return;
    }
    // Taken under the epoch: it must verify under the counter reported before it arrived.
    let counter = expected.expect("an epoch in force");
    let epoch = epoch.expect("an epoch in force");
    let Received::Accepted(Frame::Uplink(up)) =
        open(frame, &tag_key, &TagContext::Counter(counter))
    else {
        panic!("taken but no uplink under the epoch");
    };
    assert!(
        !seen.taken.contains(&(epoch, counter)),
        "counter {counter:#x} taken twice"
    );
    seen.taken.push((epoch, counter));
    assert_eq!(up.slot, slot);
    assert_eq!(follower.sync_state(), SyncState::Tracking);
    assert_eq!(follower.epoch_nonces(), Some(epoch));
    assert_eq!(follower.frame_counter(), Some(counter + 1));
    if up.input_lost {
        assert_eq!(follower.updates(), updates);
        assert!(follower.in_failsafe());
        assert_eq!(follower.failsafe_values(), &failsafe);
        return;
    }
    let mut channels = output;
    assert!(up.channels_into(&mut channels));
    assert_eq!(follower.output(), &channels);
    assert_eq!(follower.updates(), updates.wrapping_add(1));
    assert!(!follower.in_failsafe());
    seen.save_flags = if up.save_failsafe {
        seen.save_flags.saturating_add(1)
    } else {
        0
    };
    if seen.save_flags >= SAVE_FAILSAFE_FRAMES {
        assert_eq!(
            follower.failsafe_values(),
            &FailsafeValues::from_channels(&channels)
        );
    } else {
        assert_eq!(
            follower.failsafe_values(),
            &failsafe,
            "failsafe values rewritten by one frame"
        );
    }
}

/// A clean stretch of link: in each of up to 600 slots, an uplink slot brings the master's
/// frame of that slot (its nonce in the handshake, else channels under the reported counter)
/// — which must be taken, moving the counter on by one — and a downlink slot is skipped. The
/// way to the wraps of the slot counter under an epoch in force.
fn clean_run(
    follower: &mut Follower,
    key: &LinkKey,
    params: &LinkParams,
    input: &mut Input,
    now: u64,
    seen: &mut Seen,
) {
    let schedule = params.schedule();
    let mut packed = [0u8; 22];
    for byte in packed.iter_mut() {
        *byte = input.u8();
    }
    let packed = &packed[..params.format.packed_bytes()];
    for _ in 0..input.u16() % 600 {
        let Some((slot, _)) = follower.tracked_slot() else {
            return;
        };
        if schedule.kind(u32::from(slot)) == SlotKind::Downlink {
            follower.on_skipped();
            seen.observe(follower);
            continue;
        }
        let mut buf = [0u8; 64];
        let updates = follower.updates();
        if let Some(follower_nonce) = follower.handshake_nonce() {
            // The master's nonce under ours ends the handshake, whatever its value.
            let nonce = u64::from(input.u32()).max(1);
            let context = TagContext::MasterNonce { follower_nonce };
            let frame = Frame::MasterNonce { slot, nonce };
            let n = seal(&frame, key, &context, &mut buf).expect("fits");
            follower.on_received(packet(n), &buf[..n], now);
            assert_eq!(
                follower.sync_state(),
                SyncState::Tracking,
                "true master nonce refused"
            );
            assert_eq!(follower.epoch_nonces(), Some((follower_nonce, nonce)));
            assert_eq!(follower.updates(), updates);
            assert_eq!(follower.frame_counter(), Some(frame_counter(0, slot) + 1));
            seen.observe(follower);
            continue;
        }
        let counter = follower.frame_counter().expect("an epoch on the grid");
        let up = Uplink {
            slot,
            stream: StreamHeader { seq: 0, ack: 0 },
            report: None,
            save_failsafe: false,
            input_lost: false,
            format: params.format,
            packed_channels: packed,
            data: &[],
        };
        let context = TagContext::Counter(counter);
        let tag_key = epoch_key(key, follower);
        let n = seal(&Frame::Uplink(up), &tag_key, &context, &mut buf).expect("fits 64 bytes");
        follower.on_received(packet(n), &buf[..n], now);
        assert_eq!(
            follower.updates(),
            updates.wrapping_add(1),
            "a true uplink refused"
        );
        let epoch = follower.epoch_nonces().expect("in force");
        seen.taken.push((epoch, counter));
        seen.save_flags = 0;
        assert_eq!(follower.sync_state(), SyncState::Tracking);
        assert_eq!(follower.frame_counter(), Some(counter + 1));
    }
}

fn packet(len: usize) -> LinkRx {
    LinkRx::Packet { len, rssi_dbm: -60 }
}

/// The key the follower's frames of the moment are tagged with: the epoch key once in force,
/// the link key before.
fn epoch_key(key: &LinkKey, follower: &Follower) -> LinkKey {
    follower
        .epoch_nonces()
        .map_or(*key, |(n, m)| key.epoch_key(n, m))
}

/// A sealed master nonce: slot mostly the tracked one, tagged with the link key mostly under
/// the follower's handshake nonce, then up to one fuzzed byte flip.
fn master_nonce(input: &mut Input, follower: &Follower, key: &LinkKey) -> Vec<u8> {
    let slot = match (input.u8(), follower.tracked_slot()) {
        (0..=223, Some((slot, _))) => slot,
        _ => input.u8(),
    };
    let context = match (input.u8(), follower.handshake_nonce()) {
        (0..=223, Some(follower_nonce)) => TagContext::MasterNonce { follower_nonce },
        _ => air::any_context(input),
    };
    let nonce = u64::from(input.u32()).max(1);
    let mut buf = [0u8; 64];
    let n = seal(&Frame::MasterNonce { slot, nonce }, key, &context, &mut buf).expect("fits");
    let frame = &mut buf[..n];
    air::rare_flip(input, frame);
    frame.to_vec()
}

/// A well-formed sealed uplink: slot mostly the tracked one (while acquiring: 0 or fuzzed, so
/// the dwell channel's slot is found), tagged mostly with the epoch key under the follower's
/// counter (before an epoch: the link key in the context before one), fuzzed fields and
/// stream data, then up to two fuzzed byte flips.
fn uplink(input: &mut Input, params: &LinkParams, follower: &Follower, key: &LinkKey) -> Vec<u8> {
    let slot = air::uplink_slot(input, follower.tracked_slot());
    let context = match (input.u8(), follower.frame_counter()) {
        (0..=223, Some(counter)) => TagContext::Counter(counter),
        (0..=191, None) => TagContext::BeforeEpoch,
        _ => air::any_context(input),
    };
    let mut packed = [0u8; 22];
    let up = air::uplink(input, params.format, slot, &mut packed);
    let tag_key = match input.u8() {
        0..=239 => epoch_key(key, follower),
        _ => *key,
    };
    let sealing = Sealing::Tag {
        key: &tag_key,
        context,
    };
    air::sealed(input, &Frame::Uplink(up), sealing)
}
