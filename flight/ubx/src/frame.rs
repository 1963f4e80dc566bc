//! UBX framing: sync `B5 62`, class, id, little-endian length, payload, 8-bit Fletcher
//! checksum over class..payload. [`Parser`] takes bytes one at a time and hands out every
//! frame whose checksum is right. It never panics and never loses a good frame to garbage
//! in front of it: when a candidate frame fails (bad checksum, length beyond
//! [`MAX_PAYLOAD`]), every byte after its first sync byte is scanned again, so a real frame
//! hidden inside a false header's "payload" is still found.

use heapless::{Deque, Vec};

/// First sync byte ('µ').
pub const SYNC_1: u8 = 0xB5;
/// Second sync byte ('b').
pub const SYNC_2: u8 = 0x62;
/// Largest payload the parser keeps. NAV-PVT (92 B) and ACK (2 B) are what we read;
/// longer frames (MON-VER, NAV-SAT) are not enabled by our configuration and are skipped.
pub const MAX_PAYLOAD: usize = 128;
/// Bytes around the payload: sync (2), class, id, length (2), checksum (2).
pub const OVERHEAD: usize = 8;
/// Largest whole frame.
pub const MAX_FRAME: usize = MAX_PAYLOAD + OVERHEAD;

/// The 8-bit Fletcher checksum (CK_A, CK_B) of `bytes`.
#[must_use]
pub fn checksum<'a>(bytes: impl IntoIterator<Item = &'a u8>) -> [u8; 2] {
    let (mut a, mut b) = (0u8, 0u8);
    for &x in bytes {
        a = a.wrapping_add(x);
        b = b.wrapping_add(a);
    }
    [a, b]
}

/// One checked frame, borrowed from the parser until the next byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Frame<'a> {
    /// Message class.
    pub class: u8,
    /// Message id.
    pub id: u8,
    /// Payload (checksum verified).
    pub payload: &'a [u8],
}

/// Why [`encode`] could not build a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The payload does not fit in [`MAX_PAYLOAD`].
    TooLong,
}

/// Builds a whole frame (sync to checksum) around `payload`.
///
/// # Errors
/// [`EncodeError::TooLong`] when the payload exceeds [`MAX_PAYLOAD`].
pub fn encode(class: u8, id: u8, payload: &[u8]) -> Result<Vec<u8, MAX_FRAME>, EncodeError> {
    if payload.len() > MAX_PAYLOAD {
        return Err(EncodeError::TooLong);
    }
    Ok(frame_checked_payload(class, id, payload))
}

/// A payload whose largest size is part of its type.
pub trait BoundedPayload {
    /// Most bytes a value of this type holds.
    const MAX: usize;
    /// The payload bytes.
    fn bytes(&self) -> &[u8];
}

impl<const N: usize> BoundedPayload for [u8; N] {
    const MAX: usize = N;
    fn bytes(&self) -> &[u8] {
        self
    }
}

impl<const N: usize> BoundedPayload for Vec<u8, N> {
    const MAX: usize = N;
    fn bytes(&self) -> &[u8] {
        self
    }
}

/// [`encode`] for a payload type that always fits: its bound is checked against
/// [`MAX_PAYLOAD`] when compiling, so there is no failure left to handle (the receiver
/// configuration's fixed messages).
#[must_use]
pub fn encode_bounded<P: BoundedPayload>(class: u8, id: u8, payload: &P) -> Vec<u8, MAX_FRAME> {
    const {
        assert!(
            P::MAX <= MAX_PAYLOAD,
            "payload type larger than a UBX frame holds"
        )
    };
    frame_checked_payload(class, id, payload.bytes())
}

/// The frame around `payload`, whose length the caller checked against [`MAX_PAYLOAD`].
fn frame_checked_payload(class: u8, id: u8, payload: &[u8]) -> Vec<u8, MAX_FRAME> {
    let mut out: Vec<u8, MAX_FRAME> = Vec::new();
    // MAX_PAYLOAD (128) fits in the u16 length field.
    let [l0, l1] = (payload.len() as u16).to_le_bytes();
    let header = [class, id, l0, l1];
    let ck = checksum(header.iter().chain(payload));
    // Capacity is MAX_FRAME and the payload was checked, so these cannot fail.
    let _ = out.extend_from_slice(&[SYNC_1, SYNC_2]);
    let _ = out.extend_from_slice(&header);
    let _ = out.extend_from_slice(payload);
    let _ = out.extend_from_slice(&ck);
    out
}

/// Where the parser is inside a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
    Sync1,
    Sync2,
    Header,
    Body { total: usize },
}

/// Counters of what the parser threw away (for the console and link statistics).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Stats {
    /// Frames delivered.
    pub frames: u32,
    /// Candidate frames whose checksum was wrong.
    pub checksum_errors: u32,
    /// Candidate frames announcing a payload longer than [`MAX_PAYLOAD`].
    pub oversize: u32,
}

/// Byte-at-a-time UBX frame parser; bounded memory (two [`MAX_FRAME`] buffers), no heap.
#[derive(Debug, Clone)]
pub struct Parser {
    stage: Stage,
    /// The candidate frame so far, sync bytes included.
    buf: Vec<u8, MAX_FRAME>,
    /// Bytes of a failed candidate still to be scanned again (front first).
    rescan: Deque<u8, MAX_FRAME>,
    stats: Stats,
}

impl Default for Parser {
    fn default() -> Self {
        Self::new()
    }
}

/// Result of one byte through the state machine.
enum Step {
    More,
    Done,
    Failed,
}

impl Parser {
    /// An empty parser, looking for a sync byte.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            stage: Stage::Sync1,
            buf: Vec::new(),
            rescan: Deque::new(),
            stats: Stats {
                frames: 0,
                checksum_errors: 0,
                oversize: 0,
            },
        }
    }

    /// What was delivered and thrown away so far.
    #[must_use]
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Feeds `bytes`; `on_frame` is called for every good frame, in stream order.
    pub fn feed(&mut self, bytes: &[u8], mut on_frame: impl FnMut(Frame<'_>)) {
        for &b in bytes {
            self.push(b, &mut on_frame);
        }
    }

    /// Feeds one byte (and any bytes a failed candidate hands back for rescanning).
    pub fn push(&mut self, byte: u8, on_frame: &mut impl FnMut(Frame<'_>)) {
        let mut next = Some(byte);
        while let Some(b) = next {
            match self.step(b) {
                Step::More => {}
                Step::Done => {
                    self.stats.frames = self.stats.frames.wrapping_add(1);
                    if let Some(frame) = self.frame() {
                        on_frame(frame);
                    }
                    self.restart();
                }
                Step::Failed => {
                    // Scan again everything after the first sync byte, ahead of what was
                    // already waiting. buf + rescan never exceed one frame plus one byte:
                    // rescan only holds bytes that were in buf.
                    for &x in self.buf.iter().skip(1).rev() {
                        let _ = self.rescan.push_front(x);
                    }
                    self.restart();
                }
            }
            next = self.rescan.pop_front();
        }
    }

    fn restart(&mut self) {
        self.buf.clear();
        self.stage = Stage::Sync1;
    }

    fn frame(&self) -> Option<Frame<'_>> {
        let class = *self.buf.get(2)?;
        let id = *self.buf.get(3)?;
        let payload = self.buf.get(6..self.buf.len().checked_sub(2)?)?;
        Some(Frame { class, id, payload })
    }

    fn step(&mut self, b: u8) -> Step {
        match self.stage {
            Stage::Sync1 => {
                if b == SYNC_1 {
                    self.buf.clear();
                    let _ = self.buf.push(b);
                    self.stage = Stage::Sync2;
                }
                Step::More
            }
            Stage::Sync2 => {
                if b == SYNC_2 {
                    let _ = self.buf.push(b);
                    self.stage = Stage::Header;
                    Step::More
                } else {
                    let _ = self.buf.push(b);
                    Step::Failed
                }
            }
            Stage::Header => {
                let _ = self.buf.push(b);
                if self.buf.len() < 6 {
                    return Step::More;
                }
                let len = match (self.buf.get(4), self.buf.get(5)) {
                    (Some(&l0), Some(&l1)) => usize::from(u16::from_le_bytes([l0, l1])),
                    _ => return Step::Failed,
                };
                if len > MAX_PAYLOAD {
                    self.stats.oversize = self.stats.oversize.wrapping_add(1);
                    return Step::Failed;
                }
                self.stage = Stage::Body {
                    total: len + OVERHEAD,
                };
                Step::More
            }
            Stage::Body { total } => {
                if self.buf.push(b).is_err() {
                    return Step::Failed;
                }
                if self.buf.len() < total {
                    return Step::More;
                }
                let body_end = total - 2;
                let ok = match (self.buf.get(2..body_end), self.buf.get(body_end..total)) {
                    (Some(body), Some(ck)) => checksum(body) == ck,
                    _ => false,
                };
                if ok {
                    Step::Done
                } else {
                    self.stats.checksum_errors = self.stats.checksum_errors.wrapping_add(1);
                    Step::Failed
                }
            }
        }
    }
}
