//! Sealed downlinks and epoch nonce frames into a keyed master (`Master::with_key`, spec
//! §12.2). Nonce frames are tagged under the counter the nonce inside names
//! (`link::core::frame_counter(nonce, 0, slot)`), drawn mostly from a small pool so replays of
//! used, current and retired nonces happen; downlinks mostly under the counter the master
//! reports (`Master::frame_counter`); the rest under other counters, raw, or replayed, to fuzz
//! the rejection paths. Interleaved with planning, sending, listening, runs of skipped slots
//! (past wraps of the slot counter), new channel values, save-failsafe requests and streams.
//!
//! Invariants: the master counts a frame only if it verifies — a downlink of the current slot
//! with the epoch key under the reported counter while an epoch is in use, or a nonce frame
//! of the current slot with the link key under its nonce's counter; the telemetry stream and
//! the remote report move only on such a downlink; the epoch follows the spec's adoption
//! rules exactly (a model of §12.2 in this file: fresh follower nonces adopted, with wrap 0
//! the wrap of the slot, each adoption with a master nonce never used with that follower
//! nonce before; the current one only repeated within its wrap 0; the last 8 used ones, and
//! any while the current epoch was heard in the last downlink period, refused); the reported
//! counter is `nonce ‖ wraps ‖ slot` of that model (the bare slot before any epoch); after
//! an adoption or a repeat the next uplink sent in the nonce's wrap is the master's nonce
//! (link key, `nonce ‖ 0 ‖ slot`), every other planned uplink verifies with the epoch key
//! under the reported counter, carries the current slot and exactly the channels set, and
//! fits the mode's frame; no counter is sent twice under one epoch key *across* adoptions
//! (a replayed old follower nonce meets a fresh master nonce); LQ and the remote report
//! stay percentages.
#![no_main]

use std::collections::HashSet;

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::air::{self, Replays, Sealing};
use taulink_fuzz::{Input, link_key, seal_tagged};
use telemetry::channels::Channels;
use telemetry::frame::{Frame, NONCE_FRAME_BYTES, Received, SEALED_VERSION, open, seal};
use telemetry::link::core::{Master, Step, frame_counter};
use telemetry::link::{LinkKey, LinkParams};

/// Nonces a master remembers having used (spec §12.2: "the last 8 are kept").
const RECENT_NONCES: usize = 8;

/// The spec's epoch rules for the master (§12.2), the oracle the master is held to.
#[derive(Default)]
struct Model {
    /// Nonce in use and the master slot at which its wrap 0 began.
    current: Option<(u32, u32)>,
    /// Nonces used before, oldest first.
    retired: Vec<u32>,
    /// Master slot of the last downlink verified under `current`.
    last_heard: Option<u32>,
    /// The master's nonce of the current epoch (read from the master at adoption: drawn
    /// from its seed and the time, not modelled).
    master_nonce: u32,
    /// The master's nonce is due in the next uplink of the nonce's wrap.
    due: bool,
    /// Every (follower nonce, master nonce) adopted so far.
    epochs: HashSet<(u32, u32)>,
}

impl Model {
    /// Whether a verified nonce frame in downlink slot `slot` is taken (adopted or repeated).
    fn offer(&mut self, nonce: u32, slot: u32, ratio: u8) -> bool {
        if let Some((current, base)) = self.current
            && current == nonce
        {
            let repeated = slot.wrapping_sub(base) < 256;
            self.due |= repeated;
            return repeated;
        }
        let live = self
            .last_heard
            .is_some_and(|s| slot.wrapping_sub(s) <= u32::from(ratio));
        let start = self.retired.len().saturating_sub(RECENT_NONCES);
        if live || self.retired[start..].contains(&nonce) {
            return false;
        }
        if let Some((old, _)) = self.current {
            self.retired.push(old);
        }
        self.current = Some((nonce, slot & !0xFF));
        self.last_heard = None;
        self.due = true;
        true
    }

    /// The master's nonce frame is due in `slot`: the counter it goes under.
    fn master_nonce_due(&self, slot: u32) -> Option<u64> {
        let (nonce, base) = self.current?;
        (self.due && slot.wrapping_sub(base) < 256).then(|| frame_counter(nonce, 0, slot as u8))
    }

    fn counter(&self, slot: u32) -> u64 {
        match self.current {
            Some((nonce, base)) => frame_counter(nonce, slot.wrapping_sub(base) >> 8, slot as u8),
            None => frame_counter(0, 0, slot as u8),
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let key = link_key(&mut input);
    let params = air::params(&mut input, true);
    let pool: [u32; 4] = core::array::from_fn(|i| input.u32().max(i as u32 + 1));
    let mut master = Master::new(params)
        .with_key(key)
        .with_nonce_seed(u64::from(input.u32()));
    let mut model = Model::default();
    let mut channels: Channels = [992; 16];
    let mut now = 0u64;
    let mut buf = [0u8; 64];
    let mut heard = Replays::default();
    // (follower nonce, master nonce, counter) of every uplink sent under an epoch key.
    let mut sent: HashSet<(u32, u32, u64)> = HashSet::new();
    while !input.is_empty() {
        now = now.saturating_add(u64::from(input.u16()));
        match input.u8() % 9 {
            0..=2 => {
                let frame = match input.u8() % 8 {
                    0..=2 => nonce_frame(&mut input, &master, &key, &pool),
                    3 | 4 => downlink(&mut input, &params, &master, &key),
                    5 => seal_tagged(input.chunk(40), &key, master.frame_counter()),
                    6 if !heard.is_empty() => heard.pick(&mut input),
                    _ => input.chunk(40).to_vec(),
                };
                heard.keep(&frame);
                receive(&mut master, &mut model, &key, &frame, &mut input, now);
            }
            3 => {
                let received = master.counters().received;
                master.on_received(air::nothing(&mut input), &[], now);
                assert_eq!(master.counters().received, received);
            }
            4 | 5 => {
                let slot = master.slot();
                let step = master.plan(now, &mut buf);
                air::assert_grid(&step);
                match step {
                    Step::Transmit { len, .. } => {
                        let frame = &buf[..len];
                        assert_eq!(frame.first(), Some(&SEALED_VERSION));
                        assert!(
                            len <= params.rate.max_frame_bytes(),
                            "{len}-byte uplink at {:?} {:?}",
                            params.rate,
                            params.format
                        );
                        let counter = master.frame_counter();
                        let epoch = master.epoch_nonces();
                        if let Some(nonce_counter) = model.master_nonce_due(slot) {
                            // The master's nonce, with the link key under the follower's.
                            let (_, m) = epoch.expect("an epoch");
                            assert_eq!(
                                open(frame, &key, nonce_counter),
                                Received::Accepted(Frame::MasterNonce {
                                    slot: slot as u8,
                                    nonce: m
                                })
                            );
                            if input.bool() {
                                model.due = false;
                                master.on_sent();
                            } else {
                                master.on_skipped();
                            }
                            continue;
                        }
                        let tag_key = epoch.map_or(key, |(n, m)| key.epoch_key(n, m));
                        let Received::Accepted(Frame::Uplink(up)) = open(frame, &tag_key, counter)
                        else {
                            panic!("the master planned a frame that does not verify");
                        };
                        assert_eq!(up.slot, slot as u8);
                        assert_eq!(up.format, params.format);
                        taulink_fuzz::assert_uplink_channels(&up, &channels);
                        if input.bool() {
                            if let Some((n, m)) = epoch {
                                assert!(
                                    sent.insert((n, m, counter)),
                                    "two uplinks under counter {counter:#x} of epoch ({n:#x}, {m:#x})"
                                );
                            }
                            master.on_sent();
                        } else {
                            master.on_skipped();
                        }
                    }
                    step => air::listen_or_idle(&mut input, &mut master, step),
                }
            }
            6 => {
                // The loop fell behind: a run of skipped slots (past wraps of the counter).
                for _ in 0..input.u16() % 1024 {
                    master.on_skipped();
                }
            }
            7 => air::new_channels(&mut input, &mut master, &mut channels),
            _ => air::use_master_streams(&mut input, &mut master),
        }
        assert_eq!(master.has_epoch(), model.current.is_some());
        assert_eq!(
            master.epoch_nonces(),
            model.current.map(|(n, _)| (n, model.master_nonce))
        );
        assert_eq!(master.frame_counter(), model.counter(master.slot()));
        air::assert_master(&master);
    }
});

/// Feeds one packet in the current slot and checks the master against the model.
fn receive(
    master: &mut Master,
    model: &mut Model,
    key: &LinkKey,
    frame: &[u8],
    input: &mut Input,
    now: u64,
) {
    let slot = master.slot();
    let counter = master.frame_counter();
    let received = master.counters().received;
    let available = master.downlink_stream.available();
    let remote = master.remote_report();
    let ratio = master.params().telemetry_ratio;
    master.on_received(air::packet(input, frame), frame, now);
    let counted = master.counters().received != received;

    // What the frame is, by the harness' own reading of the spec.
    let nonce = nonce_in(frame);
    let verdict = match nonce {
        Some(nonce) => match open(frame, key, frame_counter(nonce, 0, slot as u8)) {
            Received::Accepted(Frame::Nonce { slot: s, nonce: n }) if s == slot as u8 => {
                assert_eq!(n, nonce);
                let before = model.current;
                let taken = model.offer(nonce, slot, ratio);
                if model.current != before {
                    // Adopted: the master's own nonce is new with this follower nonce.
                    let (n, m) = master.epoch_nonces().expect("adopted");
                    assert_eq!(n, nonce);
                    assert!(
                        model.epochs.insert((n, m)),
                        "epoch ({n:#x}, {m:#x}) adopted twice"
                    );
                    model.master_nonce = m;
                }
                Some(taken)
            }
            _ => None,
        },
        None => None,
    };
    let downlink = match (nonce, model.current) {
        (None, Some((n, _))) => match open(frame, &key.epoch_key(n, model.master_nonce), counter) {
            Received::Accepted(Frame::Downlink(down)) if down.slot == slot as u8 => Some(down),
            _ => None,
        },
        _ => None,
    };
    match (verdict, downlink) {
        (Some(taken), _) => {
            assert_eq!(counted, taken, "nonce frame: the master and §12.2 disagree");
            assert_eq!(master.downlink_stream.available(), available);
            assert_eq!(master.remote_report(), remote);
        }
        (None, Some(down)) => {
            assert!(counted, "a verified downlink of this slot was refused");
            model.last_heard = Some(slot);
            assert_eq!(master.remote_report(), down.report.or(remote));
        }
        (None, None) => {
            assert!(!counted, "counted a frame that does not verify");
            assert_eq!(master.downlink_stream.available(), available);
            assert_eq!(master.remote_report(), remote);
        }
    }
    if counted {
        assert_eq!(master.last_downlink_us(), Some(now));
    }
}

/// The nonce a sealed nonce frame names (kind byte `0x44`, exactly slot and nonce), if the
/// packet has that shape.
fn nonce_in(frame: &[u8]) -> Option<u32> {
    match frame {
        [SEALED_VERSION, 0x44, _slot, a, b, c, d, _, _, _, _] => {
            let nonce = u32::from_le_bytes([*a, *b, *c, *d]);
            (nonce != 0).then_some(nonce)
        }
        _ => None,
    }
}

/// A sealed nonce frame: nonce mostly from the pool, slot mostly the current one, tagged
/// mostly under the counter its nonce names, then up to one fuzzed byte flip.
fn nonce_frame(input: &mut Input, master: &Master, key: &LinkKey, pool: &[u32; 4]) -> Vec<u8> {
    let nonce = match input.u8() {
        0..=191 => pool[usize::from(input.u8()) % pool.len()],
        _ => input.u32().max(1),
    };
    let slot = if input.u8() < 224 {
        master.slot() as u8
    } else {
        input.u8()
    };
    let counter = if input.u8() < 224 {
        frame_counter(nonce, 0, slot)
    } else {
        air::any_counter(input)
    };
    let mut buf = [0u8; NONCE_FRAME_BYTES];
    let n = seal(&Frame::Nonce { slot, nonce }, key, counter, &mut buf).expect("fits");
    let frame = &mut buf[..n];
    air::rare_flip(input, frame);
    frame.to_vec()
}

/// A well-formed sealed downlink: slot mostly the master's current one, tagged mostly with
/// the epoch key under the master's counter, fuzzed report and stream, then up to two fuzzed
/// byte flips.
fn downlink(input: &mut Input, params: &LinkParams, master: &Master, key: &LinkKey) -> Vec<u8> {
    let slot = air::mostly(input, master.slot() as u8);
    let counter = if input.u8() < 224 {
        master.frame_counter()
    } else {
        air::any_counter(input)
    };
    let key = match (master.epoch_nonces(), input.u8()) {
        (Some((n, m)), 0..=239) => key.epoch_key(n, m),
        _ => *key,
    };
    let down = air::downlink(input, slot, params.rate.max_frame_bytes());
    let sealing = Sealing::Tag { key: &key, counter };
    air::sealed(input, &Frame::Downlink(down), sealing)
}
