//! Sealed downlinks and epoch nonce frames into a keyed master (`Master::with_key`, spec
//! §12.2). Nonce frames carry 64-bit nonces drawn mostly from a small pool, so replays of
//! used, current, pending and retired nonces happen, tagged mostly with the link key in the
//! follower's nonce context and sometimes with the proof of a known epoch; downlinks mostly
//! with the key of the epoch in force or the pending one under the counter the master
//! reports; the rest under other contexts, raw, or replayed, to fuzz the rejection paths.
//! Interleaved with planning, sending, listening, runs of skipped slots (past wraps of the
//! slot counter), new channel values, save-failsafe requests and streams.
//!
//! Invariants: the epochs follow a model of §12.2 in this file exactly — a verified nonce
//! frame of the current slot is refused in the last slot of a wrap, repeated only as the
//! last adopted nonce within its wrap 0, refused if used (the last 8 retired, the one in
//! force, the pending one), adopted at once with the proof of a known epoch's key, and
//! without one only while the epoch in force has never been heard or was not heard within
//! the live window, and not twice in a wrap; the first epoch is in force at once, later ones
//! pending until a downlink of the slot verifies under them; the master's nonce is new with
//! each follower nonce. The master counts exactly the taken nonce frames and the verified
//! downlinks of the current slot; the stream and the remote report move only on the latter;
//! the reported counter, the epochs in force and pending and the handshake counts are the
//! model's; after an adoption or a repeat the next uplink sent in the nonce's wrap is the
//! master's nonce (link key, under the follower's nonce); every other planned uplink verifies
//! under the epoch in force (or, before any, in the context no follower checks), carries the
//! current slot and exactly the channels set, and fits the mode's frame; no counter is sent
//! twice under one epoch; LQ and the remote report stay percentages.
#![no_main]

use std::collections::HashSet;

use libfuzzer_sys::fuzz_target;
use taulink_fuzz::air::{self, Replays, Sealing};
use taulink_fuzz::{Input, link_key, seal_tagged};
use telemetry::channels::Channels;
use telemetry::frame::{Frame, Received, SEALED_VERSION, open, seal};
use telemetry::link::auth::TagContext;
use telemetry::link::core::follower::DEFAULT_FAILSAFE_US;
use telemetry::link::core::{Master, Step, frame_counter};
use telemetry::link::{LinkKey, LinkParams};

/// Nonces a master remembers having retired (spec §12.2: "the last 8 are kept").
const RECENT_NONCES: usize = 8;

/// An epoch adopted: both nonces and the master slot where its wrap 0 began.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Epoch {
    follower: u64,
    master: u64,
    base: u32,
}

impl Epoch {
    fn key(&self, link: &LinkKey) -> LinkKey {
        link.epoch_key(self.follower, self.master)
    }

    fn counter(&self, slot: u32) -> u64 {
        frame_counter(u64::from(slot.wrapping_sub(self.base) / 256), slot as u8)
    }

    fn in_wrap_zero(&self, slot: u32) -> bool {
        slot.wrapping_sub(self.base) < 256
    }

    fn nonces(&self) -> (u64, u64) {
        (self.follower, self.master)
    }
}

/// What the model makes of a verified nonce frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Verdict {
    Adopted,
    Repeated,
    Refused,
}

/// The spec's epoch rules for the master (§12.2), the oracle the master is held to.
#[derive(Default)]
struct Model {
    current: Option<Epoch>,
    /// Master slot of the last downlink verified under `current`.
    current_heard: Option<u32>,
    pending: Option<Epoch>,
    /// The last epoch adopted: its master's nonce answers its follower in its wrap 0.
    answering: Option<Epoch>,
    /// Follower nonces retired, oldest first.
    retired: Vec<u64>,
    last_adoption: Option<u32>,
    /// The master's nonce is due in the next uplink of the answering epoch's wrap 0.
    due: bool,
    /// Slots within which the epoch in force counts as live once heard.
    live_slots: u32,
    adoptions: u32,
    refused: u32,
    /// Every (follower nonce, master nonce) adopted so far.
    epochs: HashSet<(u64, u64)>,
}

impl Model {
    fn new(params: &LinkParams) -> Self {
        let schedule = params.schedule();
        let live = DEFAULT_FAILSAFE_US / u64::from(schedule.slot_us());
        Self {
            live_slots: u32::try_from(live)
                .unwrap_or(u32::MAX)
                .max(u32::from(params.telemetry_ratio)),
            ..Self::default()
        }
    }

    fn judge(&self, nonce: u64, proof: Option<u32>, slot: u32, link: &LinkKey) -> Verdict {
        if slot % 256 == 255 {
            return Verdict::Refused;
        }
        if let Some(a) = self.answering
            && a.follower == nonce
        {
            return if a.in_wrap_zero(slot) {
                Verdict::Repeated
            } else {
                Verdict::Refused
            };
        }
        let recent = &self.retired[self.retired.len().saturating_sub(RECENT_NONCES)..];
        let known = [self.current, self.pending];
        if recent.contains(&nonce) || known.iter().flatten().any(|e| e.follower == nonce) {
            return Verdict::Refused;
        }
        let proven = proof.is_some_and(|p| {
            known
                .iter()
                .flatten()
                .any(|e| e.key(link).rekey_proof(nonce, slot as u8) == p)
        });
        if proven {
            return Verdict::Adopted;
        }
        let Some(heard) = self.current_heard else {
            return Verdict::Adopted;
        };
        let live = slot.wrapping_sub(heard) <= self.live_slots;
        let lately = self.last_adoption.is_some_and(|s| s / 256 == slot / 256);
        if live || lately {
            Verdict::Refused
        } else {
            Verdict::Adopted
        }
    }

    fn adopt(&mut self, epoch: Epoch, slot: u32) {
        if self.current.is_none() {
            self.current = Some(epoch);
            self.current_heard = None;
        } else if let Some(old) = self.pending.replace(epoch) {
            self.retired.push(old.follower);
        }
        self.answering = Some(epoch);
        self.last_adoption = Some(slot);
        self.adoptions += 1;
        assert!(
            self.epochs.insert(epoch.nonces()),
            "epoch {:x?} adopted twice",
            epoch.nonces()
        );
    }

    fn confirm(&mut self, slot: u32) {
        if let Some(e) = self.pending.take()
            && let Some(old) = self.current.replace(e)
        {
            self.retired.push(old.follower);
        }
        self.current_heard = Some(slot);
    }

    /// The master's nonce is due in an uplink of `slot`: the epoch it answers.
    fn master_nonce_due(&self, slot: u32) -> Option<Epoch> {
        self.answering.filter(|a| self.due && a.in_wrap_zero(slot))
    }
}

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let key = link_key(&mut input);
    let params = air::params(&mut input, true);
    let pool: [u64; 4] = core::array::from_fn(|i| u64::from(input.u32()).max(i as u64 + 1) << 7);
    let mut master = Master::new(params)
        .with_key(key)
        .with_nonce_seed(u64::from(input.u32()));
    let mut model = Model::new(&params);
    let mut channels: Channels = [992; 16];
    let mut now = 0u64;
    let mut buf = [0u8; 64];
    let mut heard = Replays::default();
    // (follower nonce, master nonce, counter) of every uplink sent under an epoch key.
    let mut sent: HashSet<(u64, u64, u64)> = HashSet::new();
    while !input.is_empty() {
        now = now.saturating_add(u64::from(input.u16()));
        match input.u8() % 9 {
            0..=2 => {
                let frame = match input.u8() % 8 {
                    0..=2 => nonce_frame(&mut input, &master, &model, &key, &pool),
                    3 | 4 => downlink(&mut input, &params, &master, &model, &key),
                    5 => {
                        let context = air::any_context(&mut input);
                        seal_tagged(input.chunk(40), &key, &context)
                    }
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
                        check_uplink(frame, &params, slot, &model, &key, &channels);
                        let counter = master.frame_counter();
                        let nonce_due = model.master_nonce_due(slot).is_some();
                        if input.bool() {
                            if nonce_due {
                                model.due = false;
                            } else if let (Some(e), Some(c)) = (model.current, counter) {
                                assert!(
                                    sent.insert((e.follower, e.master, c)),
                                    "two uplinks under counter {c:#x} of epoch {:x?}",
                                    e.nonces()
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
        assert_eq!(master.epoch_nonces(), model.current.map(|e| e.nonces()));
        assert_eq!(
            master.pending_epoch_nonces(),
            model.pending.map(|e| e.nonces())
        );
        assert_eq!(
            master.frame_counter(),
            model.current.map(|e| e.counter(master.slot()))
        );
        assert_eq!(master.handshakes(), (model.adoptions, model.refused));
        air::assert_master(&master);
    }
});

/// Checks a planned uplink of `slot`: the master's nonce when the model has it due, else
/// channels under the epoch in force (or before any, in the context nobody checks).
fn check_uplink(
    frame: &[u8],
    params: &LinkParams,
    slot: u32,
    model: &Model,
    key: &LinkKey,
    channels: &Channels,
) {
    assert_eq!(frame.first(), Some(&SEALED_VERSION));
    assert!(
        frame.len() <= params.rate.max_frame_bytes(),
        "{}-byte uplink at {:?} {:?}",
        frame.len(),
        params.rate,
        params.format
    );
    if let Some(a) = model.master_nonce_due(slot) {
        let context = TagContext::MasterNonce {
            follower_nonce: a.follower,
        };
        assert_eq!(
            open(frame, key, &context),
            Received::Accepted(Frame::MasterNonce {
                slot: slot as u8,
                nonce: a.master
            })
        );
        return;
    }
    let received = match model.current {
        Some(e) => open(frame, &e.key(key), &TagContext::Counter(e.counter(slot))),
        None => open(frame, key, &TagContext::BeforeEpoch),
    };
    let Received::Accepted(Frame::Uplink(up)) = received else {
        panic!("the master planned a frame that does not verify: {received:?}");
    };
    assert_eq!(up.slot, slot as u8);
    assert_eq!(up.format, params.format);
    taulink_fuzz::assert_uplink_channels(&up, channels);
}

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
    let received = master.counters().received;
    let available = master.downlink_stream.available();
    let remote = master.remote_report();
    master.on_received(air::packet(input, frame), frame, now);
    let counted = master.counters().received != received;

    // What the frame is, by the harness' own reading of the spec.
    if let Received::Accepted(Frame::Nonce {
        slot: s,
        nonce,
        proof,
    }) = open(frame, key, &TagContext::FollowerNonce)
    {
        let verdict = (s == slot as u8).then(|| model.judge(nonce, proof, slot, key));
        match verdict {
            Some(Verdict::Adopted) => {
                // The master's own nonce is read from it: drawn from its seed and the time.
                let (n, m) = if model.current.is_none() {
                    master.epoch_nonces()
                } else {
                    master.pending_epoch_nonces()
                }
                .expect("adopted");
                assert_eq!(n, nonce);
                let epoch = Epoch {
                    follower: n,
                    master: m,
                    base: slot & !0xFF,
                };
                model.adopt(epoch, slot);
                model.due = true;
            }
            Some(Verdict::Repeated) => model.due = true,
            Some(Verdict::Refused) => model.refused += 1,
            None => {}
        }
        let taken = matches!(verdict, Some(Verdict::Adopted | Verdict::Repeated));
        assert_eq!(counted, taken, "nonce frame: the master and §12.2 disagree");
        assert_eq!(master.downlink_stream.available(), available);
        assert_eq!(master.remote_report(), remote);
        return;
    }
    let under = |e: Option<Epoch>| {
        let e = e?;
        match open(frame, &e.key(key), &TagContext::Counter(e.counter(slot))) {
            Received::Accepted(Frame::Downlink(down)) if down.slot == slot as u8 => Some(down),
            _ => None,
        }
    };
    let down = match under(model.current) {
        Some(down) => {
            model.current_heard = Some(slot);
            Some(down)
        }
        None => {
            let down = under(model.pending);
            if down.is_some() {
                model.confirm(slot);
            }
            down
        }
    };
    match down {
        Some(down) => {
            assert!(counted, "a verified downlink of this slot was refused");
            assert_eq!(master.remote_report(), down.report.or(remote));
            assert_eq!(master.last_downlink_us(), Some(now));
        }
        None => {
            assert!(!counted, "counted a frame that does not verify");
            assert_eq!(master.downlink_stream.available(), available);
            assert_eq!(master.remote_report(), remote);
        }
    }
}

/// A sealed nonce frame: nonce mostly from the pool, slot mostly the current one, without
/// or with a proof (mostly that of a known epoch for this nonce and slot), tagged mostly
/// with the link key in the follower's nonce context, then up to one fuzzed byte flip.
fn nonce_frame(
    input: &mut Input,
    master: &Master,
    model: &Model,
    key: &LinkKey,
    pool: &[u64; 4],
) -> Vec<u8> {
    let nonce = match input.u8() {
        0..=191 => pool[usize::from(input.u8()) % pool.len()],
        _ => u64::from(input.u32()).max(1),
    };
    let slot = if input.u8() < 224 {
        master.slot() as u8
    } else {
        input.u8()
    };
    let proof = match input.u8() % 4 {
        0 => None,
        1 => Some(input.u32()),
        _ => [model.current, model.pending][usize::from(input.u8() % 2)]
            .map(|e| e.key(key).rekey_proof(nonce, slot)),
    };
    let context = if input.u8() < 224 {
        TagContext::FollowerNonce
    } else {
        air::any_context(input)
    };
    let mut buf = [0u8; 32];
    let n = seal(
        &Frame::Nonce { slot, nonce, proof },
        key,
        &context,
        &mut buf,
    )
    .expect("fits");
    let frame = &mut buf[..n];
    air::rare_flip(input, frame);
    frame.to_vec()
}

/// A well-formed sealed downlink: slot mostly the master's current one, tagged mostly with
/// the key of the epoch in force or the pending one under its counter of the slot, fuzzed
/// report and stream, then up to two fuzzed byte flips.
fn downlink(
    input: &mut Input,
    params: &LinkParams,
    master: &Master,
    model: &Model,
    key: &LinkKey,
) -> Vec<u8> {
    let slot = air::mostly(input, master.slot() as u8);
    let epoch = match input.u8() % 4 {
        0 => model.pending.or(model.current),
        _ => model.current,
    };
    let (tag_key, context) = match (epoch, input.u8()) {
        (Some(e), 0..=223) => (e.key(key), TagContext::Counter(e.counter(master.slot()))),
        (_, _) => (*key, air::any_context(input)),
    };
    let down = air::downlink(input, slot, params.rate.max_frame_bytes());
    let sealing = Sealing::Tag {
        key: &tag_key,
        context,
    };
    air::sealed(input, &Frame::Downlink(down), sealing)
}
