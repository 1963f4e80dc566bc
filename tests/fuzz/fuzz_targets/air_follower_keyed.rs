//! Sealed uplinks into a keyed follower (`Follower::with_key`, spec §12.2), through
//! acquisition, the epoch handshake (timing-only lock, nonce frames in its downlink slots) and
//! tracking under the epoch in force. Most frames are tagged under the counter the follower
//! reports it expects (`Follower::frame_counter`), so channels, flags, failsafe values and the
//! stream are reached; the rest are tagged under other counters, untagged, raw, or replays of
//! earlier frames, to fuzz the rejection paths. Interleaved with planning, sending, runs of
//! skipped slots (into resync), clean stretches of link (past wraps of the slot counter) and
//! stream use.
//!
//! The handshake ends with the master's nonce ([`Frame::MasterNonce`], link key, under the
//! follower's `nonce ‖ 0 ‖ slot`); the harness sends it (fuzzed nonce, mostly under the right
//! counter), then uplinks mostly with that epoch's key.
//!
//! Invariants: a frame is taken (channels, flags, failsafe values, stream, report) only if it
//! verifies as an uplink of the tracked slot with the epoch key under the counter reported
//! before it arrived — never while acquiring or handshaking, never with another tag; the
//! handshake ends only on a master nonce of the tracked slot verified under the handshake's
//! counter, which carries nothing else, and the epoch is then that of both nonces; no
//! (epoch, counter) is taken twice (no replay); no channels before the handshake completes;
//! an unverified frame never moves the grid of an epoch in force nor ends a handshake; the
//! counter rises by exactly one per slot within an epoch, and a true uplink of the tracked
//! slot under the reported counter is always taken; every planned downlink fits the mode's
//! frame and verifies under the reported counter, is a nonce frame carrying the epoch's
//! nonce (link key) during the handshake and a downlink of the tracked slot (epoch key)
//! after it, and no two sent under one epoch share a counter; outputs 11-bit, LQ a
//! percentage.
#![no_main]

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::air::{self, Replays, Sealing, epoch_or_any_counter as any_counter};
use taulink_fuzz::{Input, link_key, seal_tagged};
use telemetry::channels::FailsafeValues;
use telemetry::frame::{Frame, Received, SEALED_VERSION, StreamHeader, Uplink, open, seal};
use telemetry::link::auth::TAG_BYTES;
use telemetry::link::core::follower::SyncState;
use telemetry::link::core::{Follower, Step, frame_counter};
use telemetry::link::{HOP_CHANNELS, LinkKey, LinkParams, LinkRx, Schedule, SlotKind};

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
    let mut taken: Vec<(Option<(u32, u32)>, u64)> = Vec::new();
    let mut last_sent: Option<(Option<(u32, u32)>, u64)> = None;
    while !input.is_empty() {
        now = now.saturating_add(u64::from(input.u16()));
        match input.u8() % 9 {
            0..=2 => {
                let expected = follower.frame_counter();
                let frame = match input.u8() % 8 {
                    0 if follower.sync_state() == SyncState::Handshake => {
                        master_nonce(&mut input, &follower, &key)
                    }
                    0..=3 => uplink(&mut input, &params, &follower, &key),
                    4 => {
                        let counter = expected.unwrap_or_else(|| any_counter(&mut input));
                        seal_tagged(input.chunk(40), &key, counter)
                    }
                    5 if !heard.is_empty() => heard.pick(&mut input),
                    6 => {
                        let counter = any_counter(&mut input);
                        seal_tagged(input.chunk(40), &key, counter)
                    }
                    _ => input.chunk(40).to_vec(),
                };
                heard.keep(&frame);
                receive(&mut follower, &key, &frame, &mut input, now, &mut taken);
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
                        assert!(len <= params.rate.max_frame_bytes());
                        let frame = &buf[..len];
                        assert_eq!(frame.first(), Some(&SEALED_VERSION));
                        let counter = follower.frame_counter().expect("sends only with an epoch");
                        let (slot, _) = follower.tracked_slot().expect("sends only when tracking");
                        let epoch = follower.epoch_nonces();
                        let tag_key = epoch_key(&key, &follower);
                        match (open(frame, &tag_key, counter), follower.sync_state()) {
                            (
                                Received::Accepted(Frame::Nonce { slot: s, nonce }),
                                SyncState::Handshake,
                            ) => {
                                assert_eq!(s, slot);
                                assert_eq!(counter, frame_counter(nonce, 0, slot));
                            }
                            (Received::Accepted(Frame::Downlink(down)), SyncState::Tracking) => {
                                assert_eq!(down.slot, slot);
                                assert!(down.report.is_some_and(|r| r.lq_percent <= 100));
                            }
                            (other, state) => panic!("planned {other:?} in {state:?}"),
                        }
                        if input.bool() {
                            if let Some((last_epoch, last)) = last_sent
                                && last_epoch == epoch
                                && last >> 32 == counter >> 32
                            {
                                assert!(counter > last, "two downlinks under counter {counter:#x}");
                            }
                            last_sent = Some((epoch, counter));
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
                        && a >> 32 == b >> 32
                        && epoch == follower.epoch_nonces()
                    {
                        assert_eq!(a, b + 1, "the counter moves one per slot");
                    }
                }
                assert_eq!(follower.updates(), updates);
            }
            7 => clean_run(&mut follower, &key, &params, &mut input, now),
            _ => air::use_follower_streams(&mut input, &mut follower),
        }
        air::assert_follower(&follower);
        if follower.updates() == 0 {
            assert!(
                follower.in_failsafe(),
                "channels before any verified uplink"
            );
        }
        match follower.sync_state() {
            SyncState::Acquiring => assert_eq!(follower.frame_counter(), None),
            SyncState::Handshake | SyncState::Tracking => {
                let counter = follower.frame_counter().expect("an epoch");
                let (slot, channel) = follower.tracked_slot().expect("on the grid");
                assert_eq!(counter as u8, slot);
                assert_ne!(counter >> 32, 0, "nonces are never 0");
                assert!(usize::from(channel) < HOP_CHANNELS);
            }
        }
    }
});

/// Feeds one packet and checks that whatever it changed is explained by a verified uplink.
fn receive(
    follower: &mut Follower,
    key: &LinkKey,
    frame: &[u8],
    input: &mut Input,
    now: u64,
    taken: &mut Vec<(Option<(u32, u32)>, u64)>,
) {
    let expected = follower.frame_counter();
    let tag_key = epoch_key(key, follower);
    let epoch = follower.epoch_nonces();
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

    // Taken: it must verify under the counter reported before it arrived.
    let counter = expected.expect("a frame taken while acquiring");
    let (body, tag) = frame.split_at(frame.len() - TAG_BYTES);
    let tag = u32::from_le_bytes(tag.try_into().expect("4 bytes"));
    assert!(tag_key.verify(counter, body, tag), "taken with a wrong tag");
    if state == SyncState::Handshake {
        // Only the master's nonce ends a handshake, and it carries nothing else.
        let Received::Accepted(Frame::MasterNonce { slot: s, nonce: m }) =
            open(frame, key, counter)
        else {
            panic!("taken in the handshake but no master nonce");
        };
        assert_eq!(slot.map(|(t, _)| t), Some(s));
        assert_eq!(follower.sync_state(), SyncState::Tracking);
        assert_eq!(follower.epoch_nonces(), Some(((counter >> 32) as u32, m)));
        assert_eq!(follower.updates(), updates);
        assert_eq!(follower.failsafe_values(), &failsafe);
        assert_eq!(follower.uplink_stream.available(), available);
        assert_eq!(follower.remote_report(), remote);
        assert_eq!(follower.frame_counter(), Some(counter + 1));
        return;
    }
    let Received::Accepted(Frame::Uplink(up)) = open(frame, &tag_key, counter) else {
        panic!("taken but no uplink");
    };
    // A replay is a frame whose (epoch, counter) was taken before: never twice. (Only a
    // repeated pair of 32-bit nonces could make this fire legitimately.)
    assert!(
        !taken.contains(&(epoch, counter)),
        "counter {counter:#x} taken twice"
    );
    taken.push((epoch, counter));
    let (slot, _) = slot.expect("tracking or handshaking");
    assert_eq!(up.slot, slot);
    assert_eq!(follower.sync_state(), SyncState::Tracking);
    let now_counter = follower.frame_counter().expect("in force");
    assert_eq!(
        now_counter >> 32,
        counter >> 32,
        "the handshake's nonce is the epoch"
    );
    assert_eq!(follower.epoch_nonces(), epoch);
    assert_eq!(now_counter, counter + 1);
    if up.input_lost {
        assert_eq!(follower.updates(), updates);
        assert!(follower.in_failsafe());
    } else {
        let mut channels = output;
        assert!(up.channels_into(&mut channels));
        assert_eq!(follower.output(), &channels);
        assert_eq!(follower.updates(), updates.wrapping_add(1));
        assert!(!follower.in_failsafe());
        if up.save_failsafe {
            assert_eq!(
                follower.failsafe_values(),
                &FailsafeValues::from_channels(&channels)
            );
        } else {
            assert_eq!(follower.failsafe_values(), &failsafe);
        }
    }
}

/// A clean stretch of link: in each of up to 600 slots, an uplink slot brings the master's
/// frame of that slot sealed under the counter the follower reports — which must be taken,
/// moving the counter on by one — and a downlink slot is skipped. The way to the wraps of the
/// slot counter under an epoch in force.
fn clean_run(
    follower: &mut Follower,
    key: &LinkKey,
    params: &LinkParams,
    input: &mut Input,
    now: u64,
) {
    let schedule = Schedule {
        rate: params.rate,
        telemetry_ratio: params.telemetry_ratio,
    };
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
            continue;
        }
        let counter = follower.frame_counter().expect("an epoch on the grid");
        if follower.sync_state() == SyncState::Handshake {
            // The master's nonce under ours ends the handshake, whatever its value.
            let nonce = input.u32().max(1);
            let mut buf = [0u8; 64];
            let n =
                seal(&Frame::MasterNonce { slot, nonce }, key, counter, &mut buf).expect("fits");
            let outcome = LinkRx::Packet {
                len: n,
                rssi_dbm: -60,
            };
            let updates = follower.updates();
            follower.on_received(outcome, &buf[..n], now);
            assert_eq!(
                follower.sync_state(),
                SyncState::Tracking,
                "true master nonce refused"
            );
            assert_eq!(
                follower.epoch_nonces(),
                Some(((counter >> 32) as u32, nonce))
            );
            assert_eq!(follower.updates(), updates);
            assert_eq!(follower.frame_counter(), Some(counter + 1));
            continue;
        }
        let tag_key = epoch_key(key, follower);
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
        let mut buf = [0u8; 64];
        let n = seal(&Frame::Uplink(up), &tag_key, counter, &mut buf).expect("fits 64 bytes");
        let updates = follower.updates();
        let outcome = LinkRx::Packet {
            len: n,
            rssi_dbm: -60,
        };
        follower.on_received(outcome, &buf[..n], now);
        assert_eq!(
            follower.updates(),
            updates.wrapping_add(1),
            "a true uplink refused"
        );
        assert_eq!(follower.sync_state(), SyncState::Tracking);
        assert_eq!(follower.frame_counter(), Some(counter + 1));
    }
}

/// The key the follower's frames of the moment are tagged with: the epoch key once in force,
/// the link key before.
fn epoch_key(key: &LinkKey, follower: &Follower) -> LinkKey {
    follower
        .epoch_nonces()
        .map_or(*key, |(n, m)| key.epoch_key(n, m))
}

/// A sealed master nonce: slot mostly the tracked one, tagged with the link key mostly under
/// the follower's handshake counter, then up to one fuzzed byte flip.
fn master_nonce(input: &mut Input, follower: &Follower, key: &LinkKey) -> Vec<u8> {
    let slot = match (input.u8(), follower.tracked_slot()) {
        (0..=223, Some((slot, _))) => slot,
        _ => input.u8(),
    };
    let counter = match (input.u8(), follower.frame_counter()) {
        (0..=223, Some(counter)) => counter,
        _ => any_counter(input),
    };
    let nonce = input.u32().max(1);
    let mut buf = [0u8; 64];
    let n = seal(&Frame::MasterNonce { slot, nonce }, key, counter, &mut buf).expect("fits");
    let frame = &mut buf[..n];
    air::rare_flip(input, frame);
    frame.to_vec()
}

/// A well-formed sealed uplink: slot mostly the tracked one (while acquiring: 0 or fuzzed, so
/// the dwell channel's slot is found), tagged mostly under the follower's counter, fuzzed
/// fields and stream data, then up to two fuzzed byte flips.
fn uplink(input: &mut Input, params: &LinkParams, follower: &Follower, key: &LinkKey) -> Vec<u8> {
    let slot = air::uplink_slot(input, follower.tracked_slot());
    let counter = match (input.u8(), follower.frame_counter()) {
        (0..=223, Some(counter)) => counter,
        _ => any_counter(input),
    };
    let mut packed = [0u8; 22];
    let up = air::uplink(input, params.format, slot, &mut packed);
    let tag_key = match input.u8() {
        0..=239 => epoch_key(key, follower),
        _ => *key,
    };
    let sealing = Sealing::Tag {
        key: &tag_key,
        counter,
    };
    air::sealed(input, &Frame::Uplink(up), sealing)
}
