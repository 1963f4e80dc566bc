//! The two state machines driven against each other by hand, no radio: acquisition,
//! tracking, downlink exchange, failsafe timing and resync.

use super::follower::{DEFAULT_FAILSAFE_US, RESYNC_MISSES, SyncState};
use super::*;
use crate::channels::{ChannelFormat, FailsafeValues};
use crate::link::hopping::HOP_CHANNELS;
use crate::link::radio::LinkRx;
use crate::link::{Band, LinkParams, RateMode};

pub(super) const SLOT_US: u64 = 4_000;

pub(super) fn pair() -> (Master, Follower) {
    let params = LinkParams::new(
        0xC0FF_EE11,
        Band::Mhz433,
        RateMode::F250,
        ChannelFormat::Full16,
        4,
    );
    (
        Master::new(params),
        Follower::new(params, FailsafeValues::default(), DEFAULT_FAILSAFE_US),
    )
}

/// Runs master slots from `slot_start` until one is an uplink on `channel`; returns that
/// frame and when it has fully arrived.
fn next_uplink_on(master: &mut Master, slot_start: &mut u64, channel: u8) -> (Vec<u8>, u64) {
    for _ in 0..1000 {
        let mut buf = [0u8; 64];
        let start = *slot_start;
        *slot_start += SLOT_US;
        match master.plan(start, &mut buf) {
            Step::Transmit {
                channel: c, len, ..
            } if c == channel => {
                master.on_sent();
                let end = start + u64::from(master.schedule().packet_end_offset_us(len));
                return (buf[..len].to_vec(), end);
            }
            Step::Transmit { .. } => master.on_sent(),
            _ => master.finish_listen(),
        }
    }
    panic!("channel {channel} never used");
}

#[test]
fn follower_acquires_then_tracks_the_master() {
    let (mut master, mut follower) = pair();
    let channels: crate::channels::Channels = core::array::from_fn(|i| 200 + 100 * i as u16);
    master.set_channels(&channels);
    assert!(follower.in_failsafe());
    let mut buf = [0u8; 64];
    let Step::Listen {
        channel, until_us, ..
    } = follower.plan(0, &mut buf)
    else {
        panic!()
    };
    // Dwell: a whole hop cycle plus one slot on one channel, listened in windows of at most
    // MAX_LISTEN_US (the loop's hooks run between them).
    let dwell_end = 33 * SLOT_US;
    assert_eq!(until_us, MAX_LISTEN_US);
    let mut at = until_us;
    while at < dwell_end {
        let mut probe = [0u8; 64];
        let Step::Listen {
            channel: c,
            until_us: u,
            ..
        } = follower.plan(at, &mut probe)
        else {
            panic!()
        };
        assert_eq!(c, channel, "same channel for the whole dwell");
        assert!(u - at <= MAX_LISTEN_US && u <= dwell_end);
        at = u;
    }
    assert_eq!(at, dwell_end);
    let mut t = 1_000;
    let (frame, end) = next_uplink_on(&mut master, &mut t, channel);
    assert!(end < dwell_end);
    follower.on_received(
        LinkRx::Packet {
            len: frame.len(),
            rssi_dbm: -70,
        },
        &frame,
        end,
    );
    assert_eq!(follower.sync_state(), SyncState::Tracking);
    assert!(!follower.in_failsafe());
    assert_eq!(follower.output(), &channels);
    // Tracking: the next step listens for the master's next slot on its channel, opening
    // RX_EARLY_US before that slot starts.
    let master_next = master.slot();
    let Step::Listen {
        channel, from_us, ..
    } = follower.plan(end, &mut buf)
    else {
        panic!()
    };
    assert_eq!(
        follower.tracked_slot().map(|(s, _)| u32::from(s)),
        Some(master_next % 256)
    );
    assert_eq!(from_us, t - super::follower::RX_EARLY_US);
    let mut m = [0u8; 64];
    match master.plan(t, &mut m) {
        Step::Transmit { channel: c, .. } | Step::Listen { channel: c, .. } => {
            assert_eq!(c, channel)
        }
        Step::Idle => panic!(),
    }
}

/// A packet timestamped late (its read-out preempted) moves the follower's grid by at most
/// `MAX_RETIME_LATE_US`; one on time puts it back at once. Taken whole, a 400 µs late
/// timestamp opened the next window 300 µs after the master's slot start: past its preamble.
#[test]
fn a_late_timestamp_moves_the_grid_by_the_bound_only_and_an_early_one_at_once() {
    use super::follower::{MAX_RETIME_LATE_US, RX_EARLY_US};
    let (mut master, mut follower) = pair();
    let mut buf = [0u8; 64];
    let Step::Listen { channel, .. } = follower.plan(0, &mut buf) else {
        panic!()
    };
    let mut t = 0;
    let (frame, end) = next_uplink_on(&mut master, &mut t, channel);
    follower.on_received(
        LinkRx::Packet {
            len: frame.len(),
            rssi_dbm: -70,
        },
        &frame,
        end,
    );
    // The grid's lateness behind the master's, µs, after each late packet.
    let mut shift = 0;
    let mut lateness = [400, 400, 400, 0, 150].into_iter();
    let mut late = lateness.next();
    while let Some(l) = late {
        let (mut fbuf, mut mbuf) = ([0u8; 64], [0u8; 64]);
        match (master.plan(t, &mut mbuf), follower.plan(t, &mut fbuf)) {
            (Step::Transmit { len, .. }, Step::Listen { from_us, .. }) => {
                assert_eq!(from_us, t + shift - RX_EARLY_US, "lateness {shift}");
                master.on_sent();
                let end = t + u64::from(master.schedule().packet_end_offset_us(len));
                follower.on_received(LinkRx::Packet { len, rssi_dbm: -70 }, &mbuf, end + l);
                assert_eq!(follower.sync_state(), SyncState::Tracking);
                shift = l.min(shift + MAX_RETIME_LATE_US);
                late = lateness.next();
            }
            (Step::Listen { .. }, f) => {
                match f {
                    Step::Transmit { .. } => follower.on_sent(),
                    _ => follower.on_skipped(),
                }
                master.finish_listen();
            }
            other => panic!("{other:?}"),
        }
        t += SLOT_US;
    }
    assert_eq!(shift, MAX_RETIME_LATE_US, "after 0 then 150 µs late");
}

/// A tracked uplink slot's wait for a packet ends where the next slot's window opens: after a
/// miss the next window still opens `RX_EARLY_US` early. Before, it ended 75 µs before the
/// next slot on the follower's (late) grid, and the window after a miss opened past the
/// master's preamble — one missed uplink became a resync (PIL, Sparky2, issue 28).
#[test]
fn after_a_missed_uplink_the_next_window_still_opens_early() {
    use super::follower::RX_EARLY_US;
    let (mut master, mut follower) = pair();
    let mut buf = [0u8; 64];
    let Step::Listen { channel, .. } = follower.plan(0, &mut buf) else {
        panic!()
    };
    let mut t = 0;
    let (frame, end) = next_uplink_on(&mut master, &mut t, channel);
    follower.on_received(
        LinkRx::Packet {
            len: frame.len(),
            rssi_dbm: -70,
        },
        &frame,
        end,
    );
    // t is the next slot's start, an uplink slot (the lock was on slot 0 of its period).
    let Step::Listen {
        from_us, until_us, ..
    } = follower.plan(end, &mut buf)
    else {
        panic!()
    };
    assert_eq!(from_us, t - RX_EARLY_US);
    assert_eq!(until_us, t + SLOT_US - RX_EARLY_US);
    // Nothing came: the next plan, at that instant, opens the following slot's window.
    follower.on_received(LinkRx::Timeout, &[], until_us);
    let Step::Listen { from_us, .. } = follower.plan(until_us, &mut buf) else {
        panic!()
    };
    assert_eq!(from_us, t + SLOT_US - RX_EARLY_US);
}

#[test]
fn downlink_reaches_the_master_with_report_and_ack() {
    let (mut master, mut follower) = pair();
    let mut buf = [0u8; 64];
    let Step::Listen { channel, .. } = follower.plan(0, &mut buf) else {
        panic!()
    };
    let mut t = 0;
    let (frame, end) = next_uplink_on(&mut master, &mut t, channel);
    follower.on_received(
        LinkRx::Packet {
            len: frame.len(),
            rssi_dbm: -70,
        },
        &frame,
        end,
    );
    follower.downlink_stream.write(b"telemetry!");
    // Step both until the follower transmits in a downlink slot.
    for _ in 0..8 {
        let mut fbuf = [0u8; 64];
        let mut mbuf = [0u8; 64];
        let f = follower.plan(t, &mut fbuf);
        let m = master.plan(t, &mut mbuf);
        match (m, f) {
            (Step::Transmit { len, .. }, Step::Listen { .. }) => {
                master.on_sent();
                let end = t + u64::from(master.schedule().packet_end_offset_us(len));
                follower.on_received(LinkRx::Packet { len, rssi_dbm: -71 }, &mbuf, end);
            }
            (
                Step::Listen { channel: mc, .. },
                Step::Transmit {
                    channel: fc, len, ..
                },
            ) => {
                assert_eq!(mc, fc);
                follower.on_sent();
                let end = t + u64::from(master.schedule().packet_end_offset_us(len));
                assert!(master.on_received(LinkRx::Packet { len, rssi_dbm: -75 }, &fbuf, end));
                master.finish_listen();
                let mut got = [0u8; 16];
                let n = master.downlink_stream.read(&mut got);
                assert_eq!(&got[..n], b"telemetry!");
                assert_eq!(
                    master.remote_report().map(|r| (r.rssi_dbm, r.lq_percent)),
                    Some((-70, 100))
                );
                assert_eq!(master.downlink_lq(), 100);
                return;
            }
            other => panic!("{other:?}"),
        }
        t += SLOT_US;
    }
    panic!("no downlink slot");
}

#[test]
fn failsafe_exactly_after_the_configured_silence_then_resync() {
    let (mut master, mut follower) = pair();
    let mut buf = [0u8; 64];
    let Step::Listen { channel, .. } = follower.plan(0, &mut buf) else {
        panic!()
    };
    let mut t = 0;
    let (frame, end) = next_uplink_on(&mut master, &mut t, channel);
    follower.on_received(
        LinkRx::Packet {
            len: frame.len(),
            rssi_dbm: -70,
        },
        &frame,
        end,
    );
    // Step slot by slot through the silence, as the loop would.
    let (mut failsafe_at, mut resync_at) = (None, None);
    let mut now = end;
    while failsafe_at.is_none() {
        now += 500;
        let step = follower.plan(now, &mut buf);
        if follower.in_failsafe() && failsafe_at.is_none() {
            failsafe_at = Some(now);
        }
        if follower.sync_state() == SyncState::Acquiring && resync_at.is_none() {
            resync_at = Some(now);
        }
        // While acquiring, the listen must end no later than the failsafe deadline.
        if let (Step::Listen { until_us, .. }, false) = (step, follower.in_failsafe()) {
            assert!(until_us <= end + DEFAULT_FAILSAFE_US, "{until_us}");
        }
    }
    assert_eq!(failsafe_at, Some(end + DEFAULT_FAILSAFE_US));
    assert_eq!(follower.output()[2], 172, "throttle to its failsafe value");
    // RESYNC_MISSES uplinks (32) = 43 slots at 1:4 after the last packet: before failsafe at
    // F250, so the follower is already scanning when failsafe comes.
    let slots = (resync_at.unwrap() - end) / SLOT_US;
    assert!(
        (42..=44).contains(&slots),
        "{slots} slots, {RESYNC_MISSES} misses"
    );
    assert_eq!(follower.resyncs(), 1);
    assert_eq!(follower.uplink_lq(), 0, "LQ restarts after a resync");
}

#[test]
fn save_failsafe_command_stores_the_channels_on_the_follower() {
    let (mut master, mut follower) = pair();
    let channels: crate::channels::Channels = core::array::from_fn(|i| 1000 + i as u16);
    master.set_channels(&channels);
    master.request_save_failsafe();
    let mut buf = [0u8; 64];
    let Step::Listen { channel, .. } = follower.plan(0, &mut buf) else {
        panic!()
    };
    let mut t = 0;
    let (frame, end) = next_uplink_on(&mut master, &mut t, channel);
    // The flag rides in the next SAVE_FAILSAFE_REPEATS uplinks, then stops.
    let mut flagged = u8::from(frame[1] & 0x10 != 0);
    for _ in 0..16 {
        match master.plan(t, &mut buf) {
            Step::Transmit { .. } => {
                flagged += u8::from(buf[1] & 0x10 != 0);
                master.on_sent();
            }
            _ => master.finish_listen(),
        }
        t += SLOT_US;
    }
    assert_eq!(flagged, super::master::SAVE_FAILSAFE_REPEATS);
    let packet = |frame: &[u8]| LinkRx::Packet {
        len: frame.len(),
        rssi_dbm: -70,
    };
    // One flagged frame alone stores nothing (spec §6: a forgery that beat its tag must not
    // rewrite the failsafe values).
    follower.on_received(packet(&frame), &frame, end);
    assert_eq!(follower.failsafe_values(), &FailsafeValues::default());
    // The next one of the run does.
    let Step::Listen { channel, .. } = follower.plan(end, &mut buf) else {
        panic!()
    };
    let mut again = master_of(&channels);
    again.request_save_failsafe();
    let mut t2 = 0;
    let (first, _) = next_uplink_on(&mut again, &mut t2, follower_dwell_channel());
    assert_eq!(first, frame, "the same master run");
    let (second, end2) = next_uplink_on(&mut again, &mut t2, channel);
    assert_ne!(second[1] & 0x10, 0, "flagged");
    follower.on_received(packet(&second), &second, end2);
    assert_eq!(
        follower.failsafe_values(),
        &FailsafeValues::from_channels(&channels)
    );
    follower.plan(end2 + DEFAULT_FAILSAFE_US, &mut buf);
    assert!(follower.in_failsafe());
    assert_eq!(follower.output(), &channels);
}

/// A fresh master of [`pair`] sending `channels`.
fn master_of(channels: &crate::channels::Channels) -> Master {
    let (mut master, _) = pair();
    master.set_channels(channels);
    master
}

/// The hop channel a fresh follower of [`pair`] dwells on first.
fn follower_dwell_channel() -> u8 {
    let (_, mut follower) = pair();
    let mut buf = [0u8; 64];
    match follower.plan(0, &mut buf) {
        Step::Listen { channel, .. } => channel,
        other => panic!("{other:?}"),
    }
}

#[test]
fn input_lost_uplinks_put_the_follower_in_failsafe_at_once_and_keep_it_tracking() {
    let (mut master, mut follower) = pair();
    let channels: crate::channels::Channels = core::array::from_fn(|i| 1200 + i as u16);
    master.set_channels(&channels);
    let mut buf = [0u8; 64];
    let Step::Listen { channel, .. } = follower.plan(0, &mut buf) else {
        panic!()
    };
    let mut t = 0;
    let (frame, end) = next_uplink_on(&mut master, &mut t, channel);
    let packet = |frame: &[u8]| LinkRx::Packet {
        len: frame.len(),
        rssi_dbm: -70,
    };
    follower.on_received(packet(&frame), &frame, end);
    assert!(!follower.in_failsafe());
    let updates = follower.updates();

    // The master's input stops: the very next uplink it sends carries the flag.
    master.set_input_lost(true);
    master.request_save_failsafe();
    let Step::Listen { channel, .. } = follower.plan(end, &mut buf) else {
        panic!()
    };
    let (lost, lost_end) = next_uplink_on(&mut master, &mut t, channel);
    assert_eq!(
        lost[1] & 0x30,
        0x20,
        "input lost, never save-failsafe with it"
    );
    follower.on_received(packet(&lost), &lost, lost_end);
    assert!(
        follower.in_failsafe(),
        "failsafe with the first flagged uplink"
    );
    assert_eq!(follower.sync_state(), SyncState::Tracking);
    assert_eq!(
        follower.updates(),
        updates,
        "stale channels are not an update"
    );
    // Default failsafe: sticks centred, throttle low, aux held at the last flown values.
    let mut failsafe = channels;
    FailsafeValues::default().apply(&mut failsafe);
    assert_eq!(failsafe[2], 172);
    assert_eq!(follower.output(), &failsafe);
    assert_eq!(follower.failsafe_values(), &FailsafeValues::default());

    // Input back: the next uplink's channels fly again.
    master.set_input_lost(false);
    let Step::Listen { channel, .. } = follower.plan(lost_end, &mut buf) else {
        panic!()
    };
    let (back, back_end) = next_uplink_on(&mut master, &mut t, channel);
    follower.on_received(packet(&back), &back, back_end);
    assert!(!follower.in_failsafe());
    assert_eq!(follower.output(), &channels);
}

#[test]
fn tracking_follower_rejects_a_replayed_uplink_of_another_slot() {
    let (mut master, mut follower) = pair();
    let channels: crate::channels::Channels = core::array::from_fn(|i| 300 + i as u16);
    master.set_channels(&channels);
    let mut buf = [0u8; 64];
    let Step::Listen { channel, .. } = follower.plan(0, &mut buf) else {
        panic!()
    };
    let mut t = 0;
    let (first, end) = next_uplink_on(&mut master, &mut t, channel);
    let packet = |frame: &[u8]| LinkRx::Packet {
        len: frame.len(),
        rssi_dbm: -70,
    };
    follower.on_received(packet(&first), &first, end);
    assert_eq!(follower.sync_state(), SyncState::Tracking);
    let tracked = follower.tracked_slot();
    let rejected = follower.counters().rejected;
    let updates = follower.updates();

    // An attacker replays the first (recorded) uplink into the next slot's window: its
    // slot number is not the one expected, so it must neither update the channels nor
    // shift the follower's hop phase.
    let Step::Listen { .. } = follower.plan(end, &mut buf) else {
        panic!()
    };
    follower.on_received(packet(&first), &first, end + SLOT_US);
    assert_eq!(follower.counters().rejected, rejected + 1);
    assert_eq!(follower.updates(), updates);
    assert_eq!(follower.tracked_slot(), tracked, "hop phase unchanged");
}

pub(super) fn test_key(seed: u8) -> crate::link::LinkKey {
    crate::link::LinkKey::from_bytes(core::array::from_fn(|i| seed ^ (i as u8 * 17)))
}

/// The review's forgery: an attacker who knows the link's identity and hop sequence (both
/// public, heard on air) but not the key sends one uplink with full throttle and the
/// save-failsafe flag on the channel an acquiring follower dwells on. Without
/// authentication that one frame moved the follower to tracking, flew throttle 1811 and
/// overwrote its stored failsafe values. (A sealed forgery of the dwell slot may give the
/// follower timing for its epoch handshake, spec §12.2 — never channels, flags or
/// tracking.)
#[test]
fn a_forged_uplink_moves_nothing_on_an_acquiring_follower() {
    let (_, follower) = pair();
    let mut follower = follower.with_key(test_key(1));
    let mut buf = [0u8; 64];
    let Step::Listen { channel, .. } = follower.plan(0, &mut buf) else {
        panic!()
    };
    let hops = crate::link::HopSequence::new(follower.params().bind_id);
    assert_eq!(
        hops.channel(0),
        channel,
        "the attacker knows the dwell channel"
    );
    let bind_id = follower.params().bind_id;
    let mut evil: crate::channels::Channels = [992; 16];
    evil[2] = 1811;
    let mut packed = [0u8; 22];
    crate::channels::pack(&evil, ChannelFormat::Full16, &mut packed);
    let up = crate::frame::Uplink {
        slot: 0,
        stream: crate::frame::StreamHeader::default(),
        report: None,
        save_failsafe: true,
        input_lost: false,
        format: ChannelFormat::Full16,
        packed_channels: &packed,
        data: &[],
    };
    let before = *follower.failsafe_values();
    let frame = crate::frame::Frame::Uplink(up);
    let mut forged = Vec::new();
    // Keyed with the (public) bind ID, as version 1 frames are.
    let mut b = [0u8; 64];
    let n = crate::frame::encode(&frame, bind_id, &mut b).unwrap();
    forged.push(b[..n].to_vec());
    // Sealed, with guessed keys.
    for guess in [0u8, 2, 0xFF] {
        let n = crate::frame::seal(
            &frame,
            &test_key(guess),
            &crate::link::auth::TagContext::Counter(0),
            &mut b,
        )
        .unwrap();
        forged.push(b[..n].to_vec());
    }
    for (i, f) in forged.iter().enumerate() {
        let t = 1_000 * (i as u64 + 1);
        follower.on_received(
            LinkRx::Packet {
                len: f.len(),
                rssi_dbm: -40,
            },
            f,
            t,
        );
        assert_ne!(follower.sync_state(), SyncState::Tracking, "forgery {i}");
        assert!(follower.in_failsafe(), "forgery {i}");
        assert_ne!(follower.output()[2], 1811, "forgery {i}");
        assert_eq!(follower.failsafe_values(), &before, "forgery {i}");
    }
    assert_eq!(follower.counters().rejected, forged.len() as u32);
    assert_eq!(follower.updates(), 0);
}

/// The hop channels the master sends uplinks on (the others carry only its listening).
fn uplink_channels(master: &mut Master) -> Vec<u8> {
    let mut t = 0;
    let mut channels = Vec::new();
    for _ in 0..HOP_CHANNELS {
        let mut buf = [0u8; 64];
        match master.plan(t, &mut buf) {
            Step::Transmit { channel, .. } => {
                master.on_sent();
                channels.push(channel);
            }
            _ => master.finish_listen(),
        }
        t += SLOT_US;
    }
    channels
}

#[test]
fn acquisition_dwells_only_on_channels_the_master_sends_on() {
    // At 1:4 the hop indices 3, 7, …, 31 are downlink slots in every cycle (4 divides 32):
    // a dwell there waited 33 slots for nothing.
    let (mut master, mut follower) = pair();
    let uplinks = uplink_channels(&mut master);
    assert_eq!(uplinks.len(), 24);
    let mut buf = [0u8; 64];
    let mut dwelt = Vec::new();
    let mut t = 0;
    for _ in 0..HOP_CHANNELS {
        let Step::Listen { channel, .. } = follower.plan(t, &mut buf) else {
            panic!()
        };
        dwelt.push(channel);
        t += 33 * SLOT_US;
    }
    for c in &dwelt {
        assert!(uplinks.contains(c), "dwelt on {c}, never an uplink channel");
    }
    for c in &uplinks {
        assert!(dwelt.contains(c), "uplink channel {c} never dwelt on");
    }
}

#[test]
fn the_link_returns_within_one_dwell_of_the_path_whatever_the_phase() {
    // Both ends in lockstep. The follower starts (a flight controller booting) at master slot
    // `start` with the path cut; it scans, and the path returns `cut` slots later. Over every
    // phase of the scan against the master's hop cycle it takes the master's channels within
    // one dwell (33 slots) and the skipped downlink slot of the path's return, counting the
    // slot that carried them; before, a dwell on a downlink-only channel could come first
    // (66 slots).
    let mut worst = 0;
    for start in 0..HOP_CHANNELS as u32 {
        for cut in [1, 40, 90, 150, 210] {
            let (mut master, _) = pair();
            let (_, mut follower) = pair();
            let mut t = 0;
            let mut back = None;
            for n in 0..start + cut + 100 {
                let (mut mb, mut fb) = ([0u8; 64], [0u8; 64]);
                let m = master.plan(t, &mut mb);
                let f = (n >= start).then(|| follower.plan(t, &mut fb));
                if let Step::Transmit { .. } = m {
                    master.on_sent();
                } else {
                    master.finish_listen();
                }
                match (m, f) {
                    (
                        Step::Transmit { channel, len, .. },
                        Some(Step::Listen { channel: c, .. }),
                    ) if c == channel && n >= start + cut => {
                        let end = t + u64::from(master.schedule().packet_end_offset_us(len));
                        let packet = LinkRx::Packet { len, rssi_dbm: -70 };
                        follower.on_received(packet, &mb[..len], end);
                    }
                    (_, Some(Step::Transmit { .. })) => follower.on_sent(),
                    (_, Some(Step::Idle)) => follower.on_skipped(),
                    _ => {}
                }
                t += SLOT_US;
                if n >= start + cut && back.is_none() && !follower.in_failsafe() {
                    back = Some(n + 1 - (start + cut));
                }
            }
            let back = back.expect("link back");
            assert!(
                back <= 34,
                "start {start}, cut {cut}: back after {back} slots"
            );
            worst = worst.max(back);
        }
    }
    // The scan does reach its worst case of one dwell.
    assert!(worst > 24, "{worst}");
}

#[test]
fn the_uplink_length_is_known_before_its_channels_are_latched() {
    // `uplink_len` starts the radio's packet; the channels are latched and `plan` builds the
    // frame afterwards: the same length although the application queued more telemetry
    // meanwhile, the new channels, and the stream bytes `uplink_len` saw (not skipped).
    let (mut master, _) = pair();
    master.uplink_stream.write(&[1, 2, 3]);
    let mut buf = [0u8; 64];
    let len = master.uplink_len().unwrap();
    master.uplink_stream.write(&[4; 40]);
    master.set_channels(&[1_800; 16]);
    let Step::Transmit { len: built, .. } = master.plan(0, &mut buf) else {
        panic!("an uplink slot");
    };
    assert_eq!(built, len);
    let crate::frame::Received::Accepted(crate::frame::Frame::Uplink(up)) =
        crate::frame::decode(&buf[..len], master.params().bind_id)
    else {
        panic!("a valid uplink");
    };
    assert_eq!(up.stream.seq, 0);
    assert_eq!(up.data, &[1, 2, 3]);
    let mut channels = [0u16; 16];
    assert!(crate::channels::unpack(
        up.packed_channels,
        ChannelFormat::Full16,
        &mut channels
    ));
    assert_eq!(channels, [1_800; 16]);
    // The next slot's uplink goes on with the queued bytes.
    master.on_sent();
    let len = master.uplink_len().unwrap();
    let Step::Transmit { len: next, .. } = master.plan(SLOT_US, &mut buf) else {
        panic!("an uplink slot");
    };
    assert_eq!(next, len);
    let crate::frame::Received::Accepted(crate::frame::Frame::Uplink(up)) =
        crate::frame::decode(&buf[..len], master.params().bind_id)
    else {
        panic!("a valid uplink");
    };
    assert_eq!(up.stream.seq, 3);
    assert!(up.data.iter().all(|b| *b == 4) && !up.data.is_empty());
}

#[test]
fn the_counted_uplink_length_is_the_built_one_in_every_state() {
    // Both ends in lockstep over every rate mode, keyed (with the epoch handshake's nonce
    // frames) and not, with reports after downlinks, a lost downlink now and then, and the
    // uplink stream empty, partly filled and full: the length `uplink_len` counts is the
    // length `plan` then builds, and the frame goes through.
    let modes = [
        (RateMode::L50, ChannelFormat::Compact8),
        (RateMode::M100, ChannelFormat::Full16),
        (RateMode::F250, ChannelFormat::Full16),
        (RateMode::F500, ChannelFormat::Full16),
        (RateMode::F700, ChannelFormat::Sticks16),
    ];
    for (rate, format) in modes {
        for keyed in [false, true] {
            let params = LinkParams::new(0xC0FF_EE11, Band::Mhz433, rate, format, 4);
            let slot_us = u64::from(params.schedule().slot_us());
            let mut master = Master::new(params);
            let mut follower = Follower::new(params, FailsafeValues::default(), 1_000_000);
            if keyed {
                master = master.with_key(test_key(3)).with_nonce_seed(7);
                follower = follower.with_key(test_key(3)).with_nonce_seed(9);
            }
            let (mut counted, mut nonces, mut empty, mut taken) = (0, 0, 0, 0);
            for slot in 0..3_000u64 {
                let t = slot * slot_us;
                // Telemetry queued in bursts: empty, a few bytes, more than a frame holds.
                let burst = [0, 0, 3, 0, 90, 0, 0, 1][(slot % 8) as usize];
                master.uplink_stream.write(&vec![0x5A; burst]);
                let (mut mb, mut fb) = ([0u8; 64], [0u8; 64]);
                let len = master.uplink_len();
                let m = master.plan(t, &mut mb);
                let f = follower.plan(t, &mut fb);
                match (m, f) {
                    (
                        Step::Transmit {
                            channel,
                            len: built,
                            ..
                        },
                        f,
                    ) => {
                        assert_eq!(len, Some(built), "{rate:?} keyed {keyed} slot {slot}");
                        counted += 1;
                        nonces += usize::from(built == crate::frame::NONCE_FRAME_BYTES);
                        master.on_sent();
                        match f {
                            Step::Listen { channel: c, .. } if c == channel => {
                                let end =
                                    t + u64::from(master.schedule().packet_end_offset_us(built));
                                let rx = LinkRx::Packet {
                                    len: built,
                                    rssi_dbm: -70,
                                };
                                let before = follower.uplink_stream.available();
                                follower.on_received(rx, &mb[..built], end);
                                taken += usize::from(follower.uplink_stream.available() > before);
                            }
                            Step::Listen { .. } => {}
                            Step::Transmit { .. } => follower.on_sent(),
                            Step::Idle => follower.on_skipped(),
                        }
                    }
                    (m, Step::Transmit { len: sent, .. }) => {
                        assert_eq!(len, None);
                        follower.on_sent();
                        // Every seventh downlink is lost, so reports and acks vary.
                        if let Step::Listen { .. } = m
                            && slot % 7 != 3
                        {
                            let end = t + u64::from(master.schedule().packet_end_offset_us(sent));
                            let rx = LinkRx::Packet {
                                len: sent,
                                rssi_dbm: -72,
                            };
                            master.on_received(rx, &fb[..sent], end);
                        }
                        master.finish_listen();
                    }
                    (Step::Listen { .. }, _) => {
                        assert_eq!(len, None);
                        master.finish_listen();
                        follower.on_skipped();
                    }
                    (Step::Idle, _) => panic!("the master never idles with a FIFO-sized buffer"),
                }
                let mut sink = [0u8; 64];
                empty += usize::from(follower.uplink_stream.read(&mut sink) == 0);
            }
            assert!(counted > 1_000, "{rate:?} keyed {keyed}: {counted} uplinks");
            assert!(
                taken > 100,
                "{rate:?} keyed {keyed}: stream taken {taken} times"
            );
            assert!(empty > 100, "{rate:?} keyed {keyed}: {empty} empty reads");
            assert_eq!(nonces > 0, keyed, "{rate:?}: {nonces} master nonce frames");
        }
    }
}
