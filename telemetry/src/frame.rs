//! Air frames: the bytes TauLink puts in the Si4432's FIFO. Encoding writes into a caller
//! buffer; decoding borrows from the received buffer and never panics — a bad packet is a
//! [`Received::Rejected`] outcome. Layout and rationale: `spec/protocol.md` §5.

use crate::channels::{ChannelFormat, Channels, unpack, unpack_mask};
use crate::checksum::keyed_crc16;
use crate::link::auth::{LinkKey, TAG_BYTES, TagContext};
use crate::link::{Band, RateMode};

/// Protocol version, the first byte of every frame. Bumped on any incompatible change; a
/// receiver drops frames of other versions before looking further.
pub const PROTOCOL_VERSION: u8 = 1;
/// Version byte of authenticated link frames ([`seal`], [`open`]): the link CRC is replaced
/// by a 4-byte SipHash-2-4 tag over the frame's [`TagContext`] and the frame (spec §12).
/// Version 4: 64-bit epoch nonces, the master's nonce tagged under both nonces, a
/// follower's nonce that may carry the proof of its previous epoch (spec §12.2); ends of
/// earlier versions are refused at this byte.
pub const SEALED_VERSION: u8 = 4;
/// Version byte of bind frames (spec §5.2): version 2 is the key agreement (CPace shares
/// and confirmation tags); the bind header carries the same number, so ends of version 1
/// never hear these frames.
pub const BIND_VERSION: u8 = 2;
/// Bytes of a key-agreement share in bind frames ([`crate::link::pake::SHARE_BYTES`]).
pub const SHARE_BYTES: usize = crate::link::pake::SHARE_BYTES;
/// Bytes of a bind confirmation tag.
pub const BIND_TAG_BYTES: usize = 16;
/// Bytes of the bind session nonce in a key-agreement offer.
pub const SESSION_BYTES: usize = 8;
/// Bytes of every uplink/downlink frame before the optional parts: version, kind, slot,
/// stream seq, stream ack.
pub const LINK_HEADER_BYTES: usize = 5;
/// Link CRC bytes at the end of every frame.
pub const CRC_BYTES: usize = 2;
/// Bytes of the optional link report (RSSI, LQ).
pub const REPORT_BYTES: usize = 2;

const KIND_MASK: u8 = 0x07;
const FLAG_REPORT: u8 = 0x08;
const FLAG_SAVE_FAILSAFE: u8 = 0x10;
const FLAG_INPUT_LOST: u8 = 0x20;
/// Sealed frames only: the frame carries an epoch nonce (spec §12.2), kind byte exactly
/// `0x44` (the follower's, downlink), `0x4C` (the follower's with the proof of its previous
/// epoch: bit 3) or `0x46` (the master's, uplink).
const FLAG_NONCE: u8 = 0x40;
/// Sealed frames only: no stream data, and no stream-seq byte (it would name no byte). What
/// lets a keyed 16-channel uplink with the master's report fit a 32-byte frame (§4.1).
const FLAG_NO_STREAM: u8 = 0x80;
const RESERVED_MASK: u8 = 0xC0;

const KIND_BIND_OFFER: u8 = 0;
const KIND_BIND_ACCEPT: u8 = 1;
/// Bind frames only (version [`BIND_VERSION`]): the master's confirmation.
const KIND_BIND_CONFIRM: u8 = 7;
/// How a bind offer agrees the link key (the byte after the telemetry ratio).
const AUTH_PLAIN: u8 = 0;
const AUTH_ANONYMOUS: u8 = 1;
const AUTH_PHRASE: u8 = 2;
const KIND_RC16: u8 = 2;
const KIND_RC8: u8 = 3;
const KIND_DOWNLINK: u8 = 4;
const KIND_RC_STICKS: u8 = 5;
/// Sealed uplinks only, with [`FLAG_NONCE`]: the master's epoch nonce.
const KIND_MASTER_NONCE: u8 = 6;

/// Telemetry-stream position carried by every link frame (see `link::stream`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StreamHeader {
    /// Stream offset (mod 256) of the first data byte in this frame.
    pub seq: u8,
    /// Next stream offset (mod 256) the sender of this frame expects from its peer.
    pub ack: u8,
}

/// How well the sender of this frame hears its peer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkReport {
    /// Smoothed RSSI of the peer's packets, dBm.
    pub rssi_dbm: i8,
    /// Link quality: % of the last 100 expected packets received.
    pub lq_percent: u8,
}

/// Bind parameters the master offers; the follower stores them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BindOffer {
    /// The new link's identity.
    pub bind_id: u32,
    /// Band of the hop grid.
    pub band: Band,
    /// Rate mode of the bound link.
    pub rate: RateMode,
    /// Uplink channel format.
    pub format: ChannelFormat,
    /// One slot in `telemetry_ratio` is a downlink slot (a power of two, 2..=128).
    pub telemetry_ratio: u8,
    /// The key agreement (spec §12.1); `None`: an unauthenticated link (an explicit setting
    /// on both ends).
    pub exchange: Option<OfferExchange>,
}

/// The master's half of the key agreement in a bind offer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OfferExchange {
    /// With a binding phrase: the module's salt of its derivation
    /// ([`crate::link::phrase::PhraseSecret`]); `None`: no phrase (an anonymous agreement).
    pub salt: Option<[u8; crate::link::phrase::SALT_BYTES]>,
    /// Random per bind: with the bind ID, the CPace session.
    pub session: [u8; SESSION_BYTES],
    /// The master's CPace share.
    pub share: [u8; SHARE_BYTES],
}

/// The follower's half of the key agreement in a bind accept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AcceptExchange {
    /// The follower's CPace share.
    pub share: [u8; SHARE_BYTES],
    /// Its confirmation: the follower derived the master's key.
    pub tag: [u8; BIND_TAG_BYTES],
}

/// A decoded frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame<'a> {
    /// Master → follower on the bind channel.
    BindOffer(BindOffer),
    /// Follower → master on the bind channel: "took this offer" (with its share and
    /// confirmation tag when the offer agrees a key).
    BindAccept {
        /// The ID being accepted.
        bind_id: u32,
        /// The follower's half of the key agreement.
        exchange: Option<AcceptExchange>,
    },
    /// Master → follower on the bind channel, after a key agreement: the link's key sealed
    /// under the agreed session key, and the master's confirmation tag over it; the follower
    /// stores the link only on it.
    BindConfirm {
        /// The ID being confirmed.
        bind_id: u32,
        /// The master's confirmation tag.
        tag: [u8; BIND_TAG_BYTES],
        /// The link's key, sealed.
        sealed: [u8; crate::link::auth::KEY_BYTES],
    },
    /// Master → follower: channels, optional report, stream data.
    Uplink(Uplink<'a>),
    /// Follower → master: optional report, stream data.
    Downlink(Downlink<'a>),
    /// Follower → master, sealed links only: the epoch nonce the follower drew when it
    /// (re)acquired, sent in its downlink slots until the master uses it (spec §12.2). A
    /// downlink with kind bit 6 set and nothing but the slot, the nonce and, from a follower
    /// that was in force under an epoch before it resynced, that epoch's proof.
    Nonce {
        /// The slot it answers.
        slot: u8,
        /// The follower's epoch nonce (never 0).
        nonce: u64,
        /// [`LinkKey::rekey_proof`] of the follower's previous epoch for this nonce and slot
        /// (kind bit 3).
        proof: Option<u32>,
    },
    /// Master → follower, sealed links only: the master's epoch nonce, drawn when it adopted
    /// the follower's, tagged with the link key under both nonces
    /// ([`TagContext::MasterNonce`]: only the follower whose nonce it answers can check it)
    /// and sent instead of channels in the first uplink after each of the follower's nonce
    /// frames (spec §12.2). Kind byte `0x46`, then nothing but the slot and the nonce.
    MasterNonce {
        /// The master's slot counter (mod 256).
        slot: u8,
        /// The master's epoch nonce (never 0).
        nonce: u64,
    },
}

/// An uplink (channel) frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Uplink<'a> {
    /// The master's slot counter (mod 256): gives the follower hop index and slot phase.
    pub slot: u8,
    /// Stream position.
    pub stream: StreamHeader,
    /// How the master hears the follower, when included.
    pub report: Option<LinkReport>,
    /// "Store the current channels as failsafe values".
    pub save_failsafe: bool,
    /// The master has no fresh channels (its handset input stopped): the packed channels
    /// are stale and must not be flown; the follower enters failsafe.
    pub input_lost: bool,
    /// Channel format of `packed_channels`.
    pub format: ChannelFormat,
    /// Packed channel bytes ([`crate::channels::pack`]).
    pub packed_channels: &'a [u8],
    /// Stream data bytes.
    pub data: &'a [u8],
}

impl Uplink<'_> {
    /// Unpacks the channels into `channels` (the compact format leaves 8..15 unchanged).
    pub fn channels_into(&self, channels: &mut Channels) -> bool {
        unpack(self.packed_channels, self.format, channels)
    }

    /// [`Uplink::channels_into`], answering which channels were refreshed (bit `i` =
    /// channel `i`; [`ChannelFormat::Sticks16`]: the sticks and one aux group).
    pub fn channels_into_mask(&self, channels: &mut Channels) -> Option<u16> {
        unpack_mask(self.packed_channels, self.format, channels)
    }
}

/// A downlink (telemetry) frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Downlink<'a> {
    /// Echo of the slot it answers.
    pub slot: u8,
    /// Stream position.
    pub stream: StreamHeader,
    /// How the follower hears the master, when included.
    pub report: Option<LinkReport>,
    /// Stream data bytes.
    pub data: &'a [u8],
}

/// Why a received packet was dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejection {
    /// Shorter than the smallest frame.
    TooShort,
    /// Another protocol version.
    Version(u8),
    /// Link CRC mismatch: corrupted, or keyed with another bind ID.
    Crc,
    /// Authentication tag mismatch: forged, replayed under another counter, corrupted, or
    /// of another link key.
    Tag,
    /// Unknown kind or reserved bits set.
    UnknownKind(u8),
    /// Length or field values inconsistent with the kind.
    Malformed,
}

/// Outcome of decoding one packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Received<'a> {
    /// A valid frame.
    Accepted(Frame<'a>),
    /// Dropped, and why.
    Rejected(Rejection),
}

/// Encoding failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The output buffer is too small; this many bytes are needed.
    BufferTooSmall {
        /// Bytes the frame needs.
        needed: usize,
    },
    /// A field does not fit its wire encoding (packed channel length, telemetry ratio).
    InvalidField,
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            EncodeError::BufferTooSmall { needed } => {
                write!(f, "buffer too small, need {needed} bytes")
            }
            EncodeError::InvalidField => f.write_str("field does not fit its wire encoding"),
        }
    }
}

impl core::error::Error for EncodeError {}

/// Is `ratio` a valid telemetry ratio (power of two, 2..=128)?
pub const fn valid_telemetry_ratio(ratio: u8) -> bool {
    ratio >= 2 && ratio.is_power_of_two()
}

/// Writes `bytes` at `*at` in `out`, advancing `*at`.
fn put(out: &mut [u8], at: &mut usize, bytes: &[u8]) -> Result<(), EncodeError> {
    let end = *at + bytes.len();
    let dst = out
        .get_mut(*at..end)
        .ok_or(EncodeError::BufferTooSmall { needed: end })?;
    dst.copy_from_slice(bytes);
    *at = end;
    Ok(())
}

/// Encodes `frame` into `out`, with the link CRC keyed by `key` (the bind ID, or
/// [`crate::link::BIND_KEY`] for bind frames). Returns the frame length.
pub fn encode(frame: &Frame<'_>, key: u32, out: &mut [u8]) -> Result<usize, EncodeError> {
    if matches!(frame, Frame::Nonce { .. } | Frame::MasterNonce { .. }) {
        // The epoch nonces exist only on authenticated links.
        return Err(EncodeError::InvalidField);
    }
    let version = if is_bind(frame) {
        BIND_VERSION
    } else {
        PROTOCOL_VERSION
    };
    let mut at = encode_body(frame, version, out)?;
    let body = out
        .get(..at)
        .ok_or(EncodeError::BufferTooSmall { needed: at })?;
    let crc = keyed_crc16(key, body);
    put(out, &mut at, &crc.to_be_bytes())?;
    Ok(at)
}

/// Encodes a link frame authenticated with `key` in `context` (version [`SEALED_VERSION`],
/// tag instead of the link CRC). Bind frames are never sealed (they precede the key); asking
/// for one is [`EncodeError::InvalidField`].
pub fn seal(
    frame: &Frame<'_>,
    key: &LinkKey,
    context: &TagContext,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    if is_bind(frame) {
        return Err(EncodeError::InvalidField);
    }
    let mut at = encode_body(frame, SEALED_VERSION, out)?;
    let body = out
        .get(..at)
        .ok_or(EncodeError::BufferTooSmall { needed: at })?;
    let tag = key.tag_in(context, body);
    put(out, &mut at, &tag.to_le_bytes())?;
    Ok(at)
}

/// Whether `frame` is a bind frame (version [`BIND_VERSION`], never sealed).
const fn is_bind(frame: &Frame<'_>) -> bool {
    matches!(
        frame,
        Frame::BindOffer(_) | Frame::BindAccept { .. } | Frame::BindConfirm { .. }
    )
}

/// The frame's bytes before its CRC or tag, with `version` in byte 0.
fn encode_body(frame: &Frame<'_>, version: u8, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut at = 0usize;
    match frame {
        Frame::BindOffer(offer) => {
            if !valid_telemetry_ratio(offer.telemetry_ratio) {
                return Err(EncodeError::InvalidField);
            }
            put(out, &mut at, &[version, KIND_BIND_OFFER])?;
            put(out, &mut at, &offer.bind_id.to_le_bytes())?;
            let params = [
                offer.band.code(),
                offer.rate.code(),
                offer.format.code(),
                offer.telemetry_ratio,
            ];
            put(out, &mut at, &params)?;
            match &offer.exchange {
                None => put(out, &mut at, &[AUTH_PLAIN])?,
                Some(x) => {
                    match x.salt {
                        None => put(out, &mut at, &[AUTH_ANONYMOUS])?,
                        Some(salt) => {
                            put(out, &mut at, &[AUTH_PHRASE])?;
                            put(out, &mut at, &salt)?;
                        }
                    }
                    put(out, &mut at, &x.session)?;
                    put(out, &mut at, &x.share)?;
                }
            }
        }
        Frame::BindAccept { bind_id, exchange } => {
            put(out, &mut at, &[version, KIND_BIND_ACCEPT])?;
            put(out, &mut at, &bind_id.to_le_bytes())?;
            if let Some(x) = exchange {
                put(out, &mut at, &x.share)?;
                put(out, &mut at, &x.tag)?;
            }
        }
        Frame::BindConfirm {
            bind_id,
            tag,
            sealed,
        } => {
            put(out, &mut at, &[version, KIND_BIND_CONFIRM])?;
            put(out, &mut at, &bind_id.to_le_bytes())?;
            put(out, &mut at, tag)?;
            put(out, &mut at, sealed)?;
        }
        Frame::Uplink(up) => {
            if up.packed_channels.len() != up.format.packed_bytes() {
                return Err(EncodeError::InvalidField);
            }
            let kind = match up.format {
                ChannelFormat::Full16 => KIND_RC16,
                ChannelFormat::Compact8 => KIND_RC8,
                ChannelFormat::Sticks16 => KIND_RC_STICKS,
            };
            let mut flags = 0;
            if up.save_failsafe {
                flags |= FLAG_SAVE_FAILSAFE;
            }
            if up.input_lost {
                flags |= FLAG_INPUT_LOST;
            }
            let seq = stream_seq(version, up.stream, up.data);
            put_link_header(out, &mut at, version, kind | flags, up.slot, seq, up.report)?;
            put(out, &mut at, up.packed_channels)?;
            put(out, &mut at, up.data)?;
        }
        Frame::Downlink(down) => {
            let seq = stream_seq(version, down.stream, down.data);
            put_link_header(
                out,
                &mut at,
                version,
                KIND_DOWNLINK,
                down.slot,
                seq,
                down.report,
            )?;
            put(out, &mut at, down.data)?;
        }
        Frame::Nonce { slot, nonce, .. } | Frame::MasterNonce { slot, nonce } => {
            if *nonce == 0 {
                return Err(EncodeError::InvalidField);
            }
            let (kind, proof) = match frame {
                Frame::Nonce {
                    proof: Some(proof), ..
                } => (KIND_DOWNLINK | FLAG_REPORT, Some(proof)),
                Frame::Nonce { .. } => (KIND_DOWNLINK, None),
                _ => (KIND_MASTER_NONCE, None),
            };
            put(out, &mut at, &[version, kind | FLAG_NONCE, *slot])?;
            put(out, &mut at, &nonce.to_le_bytes())?;
            if let Some(proof) = proof {
                put(out, &mut at, &proof.to_le_bytes())?;
            }
        }
    }
    Ok(at)
}

/// The stream header as it goes on air: a sealed frame without stream data drops the seq
/// byte (`None`: [`FLAG_NO_STREAM`]); version 1 frames always carry it.
fn stream_seq(version: u8, stream: StreamHeader, data: &[u8]) -> (Option<u8>, u8) {
    let seq = if version == SEALED_VERSION && data.is_empty() {
        None
    } else {
        Some(stream.seq)
    };
    (seq, stream.ack)
}

fn put_link_header(
    out: &mut [u8],
    at: &mut usize,
    version: u8,
    kind_and_flags: u8,
    slot: u8,
    (seq, ack): (Option<u8>, u8),
    report: Option<LinkReport>,
) -> Result<(), EncodeError> {
    let flag = if report.is_some() { FLAG_REPORT } else { 0 };
    match seq {
        Some(seq) => put(out, at, &[version, kind_and_flags | flag, slot, seq, ack])?,
        None => put(
            out,
            at,
            &[version, kind_and_flags | flag | FLAG_NO_STREAM, slot, ack],
        )?,
    }
    if let Some(r) = report {
        put(out, at, &[r.rssi_dbm.to_ne_bytes()[0], r.lq_percent])?;
    }
    Ok(())
}

/// Decodes one received packet, checking the link CRC with `key`. Never panics.
pub fn decode(packet: &[u8], key: u32) -> Received<'_> {
    match decode_inner(packet, key) {
        Ok(frame) => Received::Accepted(frame),
        Err(why) => Received::Rejected(why),
    }
}

fn decode_inner(packet: &[u8], key: u32) -> Result<Frame<'_>, Rejection> {
    let (body, crc) = packet
        .split_at_checked(packet.len().saturating_sub(CRC_BYTES))
        .ok_or(Rejection::TooShort)?;
    let [version, kind_byte, rest @ ..] = body else {
        return Err(Rejection::TooShort);
    };
    if *version != PROTOCOL_VERSION && *version != BIND_VERSION {
        return Err(Rejection::Version(*version));
    }
    let [c0, c1] = crc else {
        return Err(Rejection::TooShort);
    };
    if keyed_crc16(key, body) != u16::from_be_bytes([*c0, *c1]) {
        return Err(Rejection::Crc);
    }
    if *version == BIND_VERSION {
        parse_bind(*kind_byte, rest)
    } else {
        parse_body(*kind_byte, rest, false)
    }
}

/// A bind frame's fields after the version byte (version [`BIND_VERSION`] only).
fn parse_bind(kind_byte: u8, rest: &[u8]) -> Result<Frame<'_>, Rejection> {
    let (id, rest) = rest.split_first_chunk::<4>().ok_or(Rejection::Malformed)?;
    let bind_id = u32::from_le_bytes(*id);
    match kind_byte {
        KIND_BIND_OFFER => {
            let ([band, rate, format, ratio, auth], rest) =
                rest.split_first_chunk::<5>().ok_or(Rejection::Malformed)?;
            let exchange = match (*auth, rest) {
                (AUTH_PLAIN, []) => None,
                (AUTH_ANONYMOUS, rest) => Some(offer_exchange(None, rest)?),
                (AUTH_PHRASE, rest) => {
                    let (salt, rest) = rest.split_first_chunk().ok_or(Rejection::Malformed)?;
                    Some(offer_exchange(Some(*salt), rest)?)
                }
                _ => return Err(Rejection::Malformed),
            };
            let offer = BindOffer {
                bind_id,
                band: Band::from_code(*band).ok_or(Rejection::Malformed)?,
                rate: RateMode::from_code(*rate).ok_or(Rejection::Malformed)?,
                format: ChannelFormat::from_code(*format).ok_or(Rejection::Malformed)?,
                telemetry_ratio: *ratio,
                exchange,
            };
            if !valid_telemetry_ratio(offer.telemetry_ratio) {
                return Err(Rejection::Malformed);
            }
            Ok(Frame::BindOffer(offer))
        }
        KIND_BIND_ACCEPT => {
            let exchange = match rest {
                [] => None,
                rest => {
                    let (share, tag) = rest.split_first_chunk().ok_or(Rejection::Malformed)?;
                    let tag: [u8; BIND_TAG_BYTES] =
                        tag.try_into().map_err(|_| Rejection::Malformed)?;
                    Some(AcceptExchange { share: *share, tag })
                }
            };
            Ok(Frame::BindAccept { bind_id, exchange })
        }
        KIND_BIND_CONFIRM => {
            let (tag, sealed) = rest.split_first_chunk().ok_or(Rejection::Malformed)?;
            Ok(Frame::BindConfirm {
                bind_id,
                tag: *tag,
                sealed: sealed.try_into().map_err(|_| Rejection::Malformed)?,
            })
        }
        other => Err(Rejection::UnknownKind(other)),
    }
}

/// The session and share of a key-agreement offer: exactly what is left.
fn offer_exchange(
    salt: Option<[u8; crate::link::phrase::SALT_BYTES]>,
    rest: &[u8],
) -> Result<OfferExchange, Rejection> {
    let (session, share) = rest.split_first_chunk().ok_or(Rejection::Malformed)?;
    Ok(OfferExchange {
        salt,
        session: *session,
        share: share.try_into().map_err(|_| Rejection::Malformed)?,
    })
}

/// Decodes one authenticated packet ([`seal`]): version [`SEALED_VERSION`], the tag checked
/// with `key` in the context the receiver expects, before any field is read. Only link
/// frames are accepted. Never panics.
pub fn open<'a>(packet: &'a [u8], key: &LinkKey, context: &TagContext) -> Received<'a> {
    match open_inner(packet, key, context) {
        Ok(frame) => Received::Accepted(frame),
        Err(why) => Received::Rejected(why),
    }
}

fn open_inner<'a>(
    packet: &'a [u8],
    key: &LinkKey,
    context: &TagContext,
) -> Result<Frame<'a>, Rejection> {
    let (body, tag) = packet
        .split_at_checked(packet.len().saturating_sub(TAG_BYTES))
        .ok_or(Rejection::TooShort)?;
    let [version, kind_byte, rest @ ..] = body else {
        return Err(Rejection::TooShort);
    };
    if *version != SEALED_VERSION {
        return Err(Rejection::Version(*version));
    }
    let [t0, t1, t2, t3] = tag else {
        return Err(Rejection::TooShort);
    };
    if !key.verify_in(context, body, u32::from_le_bytes([*t0, *t1, *t2, *t3])) {
        return Err(Rejection::Tag);
    }
    sealed_link_frame(*kind_byte, rest)
}

/// The link frame in a sealed packet, tag *not* checked: the receiver's context depends on
/// the kind of frame, and a follower takes timing (never content) from uplinks it cannot
/// verify yet (spec §12.2). Crate-private so nothing
/// outside the link cores can mistake it for an accepted frame.
pub(crate) fn peek_sealed(packet: &[u8]) -> Option<Frame<'_>> {
    let (body, _tag) = packet.split_at_checked(packet.len().checked_sub(TAG_BYTES)?)?;
    let [version, kind_byte, rest @ ..] = body else {
        return None;
    };
    if *version != SEALED_VERSION {
        return None;
    }
    sealed_link_frame(*kind_byte, rest).ok()
}

fn sealed_link_frame(kind_byte: u8, rest: &[u8]) -> Result<Frame<'_>, Rejection> {
    match parse_body(kind_byte, rest, true)? {
        frame @ (Frame::Uplink(_)
        | Frame::Downlink(_)
        | Frame::Nonce { .. }
        | Frame::MasterNonce { .. }) => Ok(frame),
        _ => Err(Rejection::Malformed),
    }
}

/// The fields after the version byte, once the CRC or tag has been checked. Kind bit 6
/// (an epoch nonce) and bit 7 (no stream data) exist only in `sealed` frames.
fn parse_body(kind_byte: u8, rest: &[u8], sealed: bool) -> Result<Frame<'_>, Rejection> {
    if sealed && kind_byte & FLAG_NONCE != 0 {
        return parse_nonce(kind_byte, rest);
    }
    let no_stream = sealed && kind_byte & FLAG_NO_STREAM != 0;
    let kind_byte = if sealed {
        kind_byte & !FLAG_NO_STREAM
    } else {
        kind_byte
    };
    if kind_byte & RESERVED_MASK != 0 {
        return Err(Rejection::UnknownKind(kind_byte));
    }
    let kind = kind_byte & KIND_MASK;
    let has_report = kind_byte & FLAG_REPORT != 0;
    let save_failsafe = kind_byte & FLAG_SAVE_FAILSAFE != 0;
    let input_lost = kind_byte & FLAG_INPUT_LOST != 0;
    match kind {
        KIND_RC16 | KIND_RC8 | KIND_RC_STICKS | KIND_DOWNLINK => {
            // Without stream data (sealed frames, bit 7) there is no seq byte; it reads 0.
            let (slot, stream, rest) = match (no_stream, rest) {
                (false, [slot, seq, ack, rest @ ..]) => (
                    slot,
                    StreamHeader {
                        seq: *seq,
                        ack: *ack,
                    },
                    rest,
                ),
                (true, [slot, ack, rest @ ..]) => (slot, StreamHeader { seq: 0, ack: *ack }, rest),
                _ => return Err(Rejection::Malformed),
            };
            let (report, rest) = if has_report {
                let (r, rest) = rest
                    .split_at_checked(REPORT_BYTES)
                    .ok_or(Rejection::Malformed)?;
                let [rssi, lq] = r else {
                    return Err(Rejection::Malformed);
                };
                if *lq > 100 {
                    return Err(Rejection::Malformed);
                }
                (
                    Some(LinkReport {
                        rssi_dbm: i8::from_ne_bytes([*rssi]),
                        lq_percent: *lq,
                    }),
                    rest,
                )
            } else {
                (None, rest)
            };
            if kind == KIND_DOWNLINK {
                if save_failsafe || input_lost || (no_stream && !rest.is_empty()) {
                    return Err(Rejection::Malformed);
                }
                return Ok(Frame::Downlink(Downlink {
                    slot: *slot,
                    stream,
                    report,
                    data: rest,
                }));
            }
            let format = match kind {
                KIND_RC16 => ChannelFormat::Full16,
                KIND_RC8 => ChannelFormat::Compact8,
                _ => ChannelFormat::Sticks16,
            };
            let (packed_channels, data) = rest
                .split_at_checked(format.packed_bytes())
                .ok_or(Rejection::Malformed)?;
            // The stick format's reserved bit (the last of its packed bytes' top bit).
            if format == ChannelFormat::Sticks16
                && packed_channels.last().is_some_and(|b| b & 0x80 != 0)
            {
                return Err(Rejection::Malformed);
            }
            if no_stream && !data.is_empty() {
                return Err(Rejection::Malformed);
            }
            Ok(Frame::Uplink(Uplink {
                slot: *slot,
                stream,
                report,
                save_failsafe,
                input_lost,
                format,
                packed_channels,
                data,
            }))
        }
        other => Err(Rejection::UnknownKind(other)),
    }
}

/// An epoch-nonce frame after its kind byte: the slot, the 64-bit nonce (never 0) and, for
/// a follower's nonce with kind bit 3, the proof of its previous epoch.
fn parse_nonce(kind_byte: u8, rest: &[u8]) -> Result<Frame<'_>, Rejection> {
    let (slot, rest) = rest.split_first().ok_or(Rejection::Malformed)?;
    let (nonce, rest) = rest.split_first_chunk::<8>().ok_or(Rejection::Malformed)?;
    let nonce = u64::from_le_bytes(*nonce);
    if nonce == 0 {
        return Err(Rejection::Malformed);
    }
    let slot = *slot;
    match (kind_byte, rest) {
        (k, []) if k == KIND_MASTER_NONCE | FLAG_NONCE => Ok(Frame::MasterNonce { slot, nonce }),
        (k, []) if k == KIND_DOWNLINK | FLAG_NONCE => Ok(Frame::Nonce {
            slot,
            nonce,
            proof: None,
        }),
        (k, [a, b, c, d]) if k == KIND_DOWNLINK | FLAG_NONCE | FLAG_REPORT => Ok(Frame::Nonce {
            slot,
            nonce,
            proof: Some(u32::from_le_bytes([*a, *b, *c, *d])),
        }),
        _ => Err(Rejection::Malformed),
    }
}

/// Frame bytes an uplink takes before its stream data.
pub const fn uplink_overhead(format: ChannelFormat, with_report: bool) -> usize {
    LINK_HEADER_BYTES
        + if with_report { REPORT_BYTES } else { 0 }
        + format.packed_bytes()
        + CRC_BYTES
}

/// Bytes of a sealed uplink of `format`, with or without the report, carrying `data` stream
/// bytes: the tag instead of the CRC, and no seq byte without stream data (spec §5.1).
pub const fn sealed_uplink_bytes(format: ChannelFormat, with_report: bool, data: usize) -> usize {
    let seq_dropped = if data == 0 { 1 } else { 0 };
    uplink_overhead(format, with_report) - CRC_BYTES + TAG_BYTES - seq_dropped + data
}

/// Bytes of a sealed [`Frame::Nonce`] without proof or a [`Frame::MasterNonce`]: version,
/// kind, slot, 64-bit nonce, tag.
pub const NONCE_FRAME_BYTES: usize = 3 + 8 + TAG_BYTES;
/// Bytes of a sealed [`Frame::Nonce`] with the proof of the previous epoch.
pub const PROVEN_NONCE_FRAME_BYTES: usize = NONCE_FRAME_BYTES + 4;

/// Frame bytes a downlink takes before its stream data.
pub const fn downlink_overhead(with_report: bool) -> usize {
    LINK_HEADER_BYTES + if with_report { REPORT_BYTES } else { 0 } + CRC_BYTES
}

#[cfg(test)]
#[path = "frame_tests.rs"]
mod tests;
