//! What the fuzz targets share: a cursor that turns the fuzzer's bytes into typed choices,
//! the two functions that make a fuzzed air frame pass the link's integrity check (the keyed
//! CRC of unkeyed ends, the tag of keyed ones), a `block_on` for the async flash stores, the
//! handset decoders' round-trip check and the OpenLRSng roles' set-up; the air-link
//! harnesses' frames, steps and invariants are in [`air`].
//!
//! Every target lives in `fuzz_targets/` and is built by `cargo fuzz build -s none` from this
//! directory (see README.md).

pub mod air;

use openlrs::bind::BindData;
use openlrs::{BindingVersion, RfmType};
use telemetry::checksum::keyed_crc16;
use telemetry::frame::CRC_BYTES;
use telemetry::link::LinkKey;
use telemetry::link::auth::{TAG_BYTES, TagContext};

/// Reads the fuzz input front to back; every read succeeds (zeros once it runs dry), so a
/// harness never has to handle "not enough input" and the fuzzer's mutations stay local.
pub struct Input<'a> {
    data: &'a [u8],
}

impl<'a> Input<'a> {
    /// A cursor at the start of `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Self { data }
    }

    /// Nothing left.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Up to `n` bytes (fewer at the end).
    pub fn bytes(&mut self, n: usize) -> &'a [u8] {
        let (head, tail) = self.data.split_at(n.min(self.data.len()));
        self.data = tail;
        head
    }

    /// One byte, 0 when empty.
    pub fn u8(&mut self) -> u8 {
        self.bytes(1).first().copied().unwrap_or(0)
    }

    /// A little-endian u16 (missing bytes are 0).
    pub fn u16(&mut self) -> u16 {
        let mut b = [0u8; 2];
        for (d, s) in b.iter_mut().zip(self.bytes(2)) {
            *d = *s;
        }
        u16::from_le_bytes(b)
    }

    /// A little-endian u32 (missing bytes are 0).
    pub fn u32(&mut self) -> u32 {
        let mut b = [0u8; 4];
        for (d, s) in b.iter_mut().zip(self.bytes(4)) {
            *d = *s;
        }
        u32::from_le_bytes(b)
    }

    /// One bit of choice.
    pub fn bool(&mut self) -> bool {
        self.u8() & 1 != 0
    }

    /// A length byte (mod `max + 1`) followed by that many bytes.
    pub fn chunk(&mut self, max: usize) -> &'a [u8] {
        let len = usize::from(self.u8()) % (max + 1);
        self.bytes(len)
    }

    /// Everything left.
    pub fn rest(&mut self) -> &'a [u8] {
        self.bytes(self.data.len())
    }
}

/// Makes a fuzzed frame body pass the receiver's integrity check, so the fuzzer explores the
/// state machine behind it instead of the check: appends today's link check, the CRC-16
/// keyed with the bind ID (unkeyed ends, protocol version 1). Keyed ends: [`seal_tagged`].
pub fn seal(body: &[u8], key: u32) -> Vec<u8> {
    let mut frame = Vec::with_capacity(body.len() + CRC_BYTES);
    frame.extend_from_slice(body);
    frame.extend_from_slice(&keyed_crc16(key, body).to_be_bytes());
    frame
}

/// Makes a fuzzed frame body pass a keyed end's tag check (spec §12.2): appends the 4-byte
/// tag of `body` under `key` in `context` — the one the receiver checks in
/// (`TagContext::Counter` of `Master::frame_counter` / `Follower::frame_counter` under the
/// epoch key, `TagContext::FollowerNonce` or `TagContext::MasterNonce` under the link key).
/// Any other context or key gives a frame that must be refused.
pub fn seal_tagged(body: &[u8], key: &LinkKey, context: &TagContext) -> Vec<u8> {
    let mut frame = Vec::with_capacity(body.len() + TAG_BYTES);
    frame.extend_from_slice(body);
    frame.extend_from_slice(&key.tag_in(context, body).to_le_bytes());
    frame
}

/// A link key from the input: mostly one of four fixed keys (so the fuzzer's corpus entries
/// stay comparable), sometimes 16 fuzzed bytes.
pub fn link_key(input: &mut Input) -> LinkKey {
    let choice = input.u8();
    let mut bytes = [choice; 16];
    if choice >= 4 {
        for (b, s) in bytes.iter_mut().zip(input.bytes(16)) {
            *b = *s;
        }
    }
    LinkKey::from_bytes(bytes)
}

/// Runs a future that never waits on anything outside itself (the mock flash) to completion.
/// embassy-futures' poll loop, not si4432-sim's `Simulation`: nothing here needs virtual
/// time, and the fuzz crate is its own workspace, kept to the crates its targets exercise.
pub fn block_on<F: core::future::Future>(future: F) -> F::Output {
    embassy_futures::block_on(future)
}

/// Checks that a planned uplink carries the channels the master was given: every channel the
/// frame's format updates in this packet (all of them for the full formats; the sticks and
/// one aux group for `Sticks16`) equals the input, clamped to the 11-bit range.
pub fn assert_uplink_channels(up: &telemetry::frame::Uplink<'_>, channels: &[u16; 16]) {
    let mut sent = [0u16; 16];
    let mask = up
        .channels_into_mask(&mut sent)
        .expect("a planned uplink's channels unpack");
    assert_ne!(mask, 0, "an uplink that updates no channel");
    for (i, (&got, &given)) in sent.iter().zip(channels.iter()).enumerate() {
        if mask & (1 << i) != 0 {
            let expected = given.min(telemetry::channels::CHANNEL_MAX);
            assert_eq!(got, expected, "channel {i}");
        }
    }
}

/// Checks a handset decoder's round trip: `wire`, a frame the decoder delivered and
/// re-encoded, decodes with a fresh decoder (`decode_all`: the decoder's `push_all`) to
/// exactly `expected`.
pub fn assert_decodes_to<E: PartialEq + core::fmt::Debug>(
    wire: &[u8],
    expected: E,
    decode_all: impl FnOnce(&[u8], &mut dyn FnMut(E)),
) {
    let mut again = Vec::new();
    decode_all(wire, &mut |e| again.push(e));
    assert_eq!(again, vec![expected]);
}

/// An OpenLRSng link's binding version and band from the input (both versions, every band).
pub fn openlrs_link(input: &mut Input) -> (BindingVersion, RfmType) {
    let version = if input.bool() {
        BindingVersion::V38
    } else {
        BindingVersion::V39
    };
    let band = [RfmType::Mhz433, RfmType::Mhz868, RfmType::Mhz915][usize::from(input.u8() % 3)];
    (version, band)
}

/// OpenLRSng's default bind data for `version` and `band` with fuzzed flags and modem
/// profile (any of the five).
pub fn openlrs_bind(input: &mut Input, version: BindingVersion, band: RfmType) -> BindData {
    let mut data = BindData::defaults(version, band);
    data.flags = input.u8();
    data.modem_profile = input.u8() % 5;
    data
}
