//! What the four air-link harnesses share (`air_master`, `air_master_keyed`, `air_follower`,
//! `air_follower_keyed`): link parameters, fuzzed frames sealed the way the end under test
//! checks them — the keyed CRC of unkeyed ends or a keyed end's tag, the one difference
//! between each pair, as [`Sealing`] — the radio's receive outcomes, the steps both ends
//! plan, the stream use and the invariants every end keeps after every step.
//!
//! Every helper reads the input in the order the harnesses always have, so corpora stay
//! valid across this split.

use telemetry::channels::{CHANNEL_MAX, ChannelFormat, Channels};
use telemetry::frame::{CRC_BYTES, Downlink, Frame, LinkReport, StreamHeader, Uplink};
use telemetry::link::auth::TagContext;
use telemetry::link::core::{Follower, Master, STREAM_RX_BYTES, Step, frame_counter};
use telemetry::link::stream::{StreamReceiver, StreamSender};
use telemetry::link::{Band, HOP_CHANNELS, LinkKey, LinkParams, LinkRx, RateMode};

use crate::Input;

/// Frames the keyed harnesses keep for replays.
pub const REPLAYS: usize = 16;

/// How the end under test checks a frame: the difference between each pair of harnesses.
#[derive(Clone, Copy)]
pub enum Sealing<'k> {
    /// Unkeyed ends: the link CRC keyed with the bind ID ([`crate::seal`]).
    Crc {
        /// The link's bind ID.
        bind_id: u32,
    },
    /// Keyed ends (spec §12.2): a tag under `key` in `context`.
    Tag {
        /// The key the frame is tagged with (link key or an epoch key).
        key: &'k LinkKey,
        /// What the tag covers besides the frame (an epoch's frame counter, a nonce's).
        context: TagContext,
    },
}

/// Link parameters from the input: any bind ID, every band, ratio, and every rate and
/// channel format the sealing allows (keyed links: neither F700 nor `Sticks16`).
pub fn params(input: &mut Input, keyed: bool) -> LinkParams {
    let (rates, formats) = if keyed { (4, 2) } else { (5, 3) };
    LinkParams {
        bind_id: input.u32(),
        band: Band::from_code(input.u8() % 3).unwrap_or(Band::Mhz433),
        rate: RateMode::from_code(input.u8() % rates).unwrap_or(RateMode::F500),
        format: ChannelFormat::from_code(input.u8() % formats).unwrap_or(ChannelFormat::Full16),
        telemetry_ratio: 2 << (input.u8() % 7),
    }
}

/// `frame` encoded and sealed, then up to two fuzzed byte flips — in the body before the CRC
/// is re-computed (unkeyed: the fuzzer explores the state machine, not the CRC check), in the
/// sealed frame (keyed: a flip must fail the tag).
pub fn sealed(input: &mut Input, frame: &Frame<'_>, sealing: Sealing<'_>) -> Vec<u8> {
    let mut buf = [0u8; 128];
    match sealing {
        Sealing::Crc { bind_id } => {
            let n = telemetry::frame::encode(frame, bind_id, &mut buf).expect("fits 128 bytes");
            let body = &mut buf[..n - CRC_BYTES];
            flips(input, body);
            crate::seal(body, bind_id)
        }
        Sealing::Tag { key, context } => {
            let n = telemetry::frame::seal(frame, key, &context, &mut buf).expect("fits 128 bytes");
            let frame = &mut buf[..n];
            flips(input, frame);
            frame.to_vec()
        }
    }
}

/// Up to two fuzzed byte flips in `bytes` (not empty).
fn flips(input: &mut Input, bytes: &mut [u8]) {
    for _ in 0..input.u8() % 3 {
        let at = usize::from(input.u8()) % bytes.len();
        bytes[at] ^= input.u8();
    }
}

/// One fuzzed byte flip in 16 frames: for the keyed ends' nonce frames.
pub fn rare_flip(input: &mut Input, frame: &mut [u8]) {
    if input.u8() < 16 {
        let at = usize::from(input.u8()) % frame.len();
        frame[at] ^= input.u8();
    }
}

/// `likely` three times in four, otherwise a fuzzed byte: the slot a master-side frame
/// mostly answers.
pub fn mostly(input: &mut Input, likely: u8) -> u8 {
    if input.u8() < 192 { likely } else { input.u8() }
}

/// The slot of an uplink for a follower: mostly the tracked one (while acquiring: 0 or
/// fuzzed, so the dwell channel's slot is found).
pub fn uplink_slot(input: &mut Input, tracked: Option<(u8, u8)>) -> u8 {
    match (input.u8(), tracked) {
        (0..=191, Some((slot, _))) => slot,
        (0..=127, None) => 0,
        (_, _) => input.u8(),
    }
}

/// Any tag context: an epoch counter (of the first wraps, or 64 fuzzed bits), either
/// nonce's, or the one before any epoch.
pub fn any_context(input: &mut Input) -> TagContext {
    match input.u8() % 6 {
        0 | 1 => TagContext::Counter(frame_counter(u64::from(input.u8() % 4), input.u8())),
        2 => TagContext::Counter(u64::from(input.u32()) << 32 | u64::from(input.u32())),
        3 => TagContext::FollowerNonce,
        4 => TagContext::MasterNonce {
            follower_nonce: u64::from(input.u32()) << 32 | u64::from(input.u32()),
        },
        _ => TagContext::BeforeEpoch,
    }
}

/// A fuzzed link report, or none.
fn report(input: &mut Input) -> Option<LinkReport> {
    input.bool().then(|| LinkReport {
        rssi_dbm: input.u8() as i8,
        lq_percent: input.u8() % 101,
    })
}

/// A fuzzed stream header.
fn stream(input: &mut Input) -> StreamHeader {
    StreamHeader {
        seq: input.u8(),
        ack: input.u8(),
    }
}

/// A well-formed downlink of `slot`: fuzzed report and stream, up to `data_max` stream bytes.
pub fn downlink<'a>(input: &mut Input<'a>, slot: u8, data_max: usize) -> Downlink<'a> {
    let report = report(input);
    Downlink {
        slot,
        stream: stream(input),
        report,
        data: input.chunk(data_max),
    }
}

/// A well-formed uplink of `slot` in `format`: fuzzed channels (packed into `packed`), report,
/// stream, flags and up to 40 stream bytes.
pub fn uplink<'b, 'a: 'b>(
    input: &mut Input<'a>,
    format: ChannelFormat,
    slot: u8,
    packed: &'b mut [u8; 22],
) -> Uplink<'b> {
    let packed = &mut packed[..format.packed_bytes()];
    for byte in packed.iter_mut() {
        *byte = input.u8();
    }
    let report = report(input);
    Uplink {
        slot,
        stream: stream(input),
        report,
        save_failsafe: input.u8() < 32,
        input_lost: input.u8() < 16,
        format,
        packed_channels: packed,
        data: input.chunk(40),
    }
}

/// The radio's outcome for `frame`, with a fuzzed RSSI.
pub fn packet(input: &mut Input, frame: &[u8]) -> LinkRx {
    LinkRx::Packet {
        len: frame.len(),
        rssi_dbm: i16::from(input.u8() as i8),
    }
}

/// A listen that brought no packet: a corrupted one or nothing.
pub fn nothing(input: &mut Input) -> LinkRx {
    if input.bool() {
        LinkRx::Corrupted
    } else {
        LinkRx::Timeout
    }
}

/// A transmission planned on a grid channel.
pub fn assert_grid(step: &Step) {
    if let Step::Transmit { channel, .. } | Step::Listen { channel, .. } = step {
        assert!(usize::from(*channel) < HOP_CHANNELS);
    }
}

/// A master's listen or idle step (its transmissions are each harness's own): the window
/// heard to its end or the slot skipped, as the input says; an idle slot skipped.
pub fn listen_or_idle(input: &mut Input, master: &mut Master, step: Step) {
    match step {
        Step::Listen {
            from_us, until_us, ..
        } => {
            assert!(from_us <= until_us);
            if input.bool() {
                master.finish_listen();
            } else {
                master.on_skipped();
            }
        }
        Step::Idle => master.on_skipped(),
        Step::Transmit { .. } => panic!("a transmission is the harness's to check"),
    }
}

/// A follower's listen or idle step planned at `now` (its transmissions are each harness's
/// own): a window that ends no earlier than it starts or than now; an idle slot skipped.
pub fn follower_listen_or_idle(follower: &mut Follower, step: Step, now: u64) {
    match step {
        Step::Listen {
            from_us, until_us, ..
        } => assert!(until_us >= from_us || until_us >= now),
        Step::Idle => follower.on_skipped(),
        Step::Transmit { .. } => panic!("a transmission is the harness's to check"),
    }
}

/// New channel values from the input for the master, sometimes with a save-failsafe
/// request.
pub fn new_channels(input: &mut Input, master: &mut Master, channels: &mut Channels) {
    for value in channels.iter_mut() {
        *value = input.u16();
    }
    master.set_channels(channels);
    if input.bool() {
        master.request_save_failsafe();
    }
}

/// Frames heard, kept for replays (the last [`REPLAYS`]).
#[derive(Default)]
pub struct Replays(Vec<Vec<u8>>);

impl Replays {
    /// Nothing heard yet.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// One of the frames heard, chosen by the input (none heard: an empty frame).
    pub fn pick(&self, input: &mut Input) -> Vec<u8> {
        if self.0.is_empty() {
            return Vec::new();
        }
        let at = usize::from(input.u8()) % self.0.len();
        self.0.get(at).cloned().unwrap_or_default()
    }

    /// Keeps `frame`, forgetting the oldest beyond [`REPLAYS`].
    pub fn keep(&mut self, frame: &[u8]) {
        if self.0.len() == REPLAYS {
            self.0.remove(0);
        }
        self.0.push(frame.to_vec());
    }
}

/// The application's stream use at the master: fuzzed bytes queued to send, up to 64 bytes
/// received read out.
pub fn use_master_streams(input: &mut Input, master: &mut Master) {
    use_streams(
        input,
        &mut master.uplink_stream,
        &mut master.downlink_stream,
    );
}

/// The application's stream use at the follower, as at the master.
pub fn use_follower_streams(input: &mut Input, follower: &mut Follower) {
    use_streams(
        input,
        &mut follower.downlink_stream,
        &mut follower.uplink_stream,
    );
}

fn use_streams<const T: usize, const R: usize>(
    input: &mut Input,
    send: &mut StreamSender<T>,
    receive: &mut StreamReceiver<R>,
) {
    send.write(input.chunk(64));
    let mut out = [0u8; 64];
    receive.read(&mut out);
}

/// What a master keeps after every step: see [`assert_end`].
pub fn assert_master(master: &Master) {
    assert_end(
        master.downlink_lq(),
        master.downlink_stream.available(),
        master.remote_report(),
    );
}

/// What a follower keeps after every step: 11-bit outputs, and [`assert_end`].
pub fn assert_follower(follower: &Follower) {
    assert!(follower.output().iter().all(|&v| v <= CHANNEL_MAX));
    assert_end(
        follower.uplink_lq(),
        follower.uplink_stream.available(),
        follower.remote_report(),
    );
}

/// What every end keeps after every step: its LQ and the remote end's are percentages, and
/// the received stream never outgrows its buffer.
fn assert_end(lq: u8, received: usize, remote: Option<LinkReport>) {
    assert!(lq <= 100);
    assert!(received <= STREAM_RX_BYTES);
    if let Some(report) = remote {
        assert!(report.lq_percent <= 100);
    }
}
