//! Streaming CRSF decoder: takes the UART's bytes in any chunking, finds frames, checks their
//! CRC, and resynchronises on garbage without dropping a frame that starts inside it.

use heapless::Vec;

use super::frame::{FRAME_CRC, Frame, MAX_FRAME_LEN, MAX_LENGTH_BYTE, MIN_LENGTH_BYTE, address};

/// Byte-0 values a frame may start with: the serial sync byte and the device addresses that
/// EdgeTX and receivers put there (radio → module uses 0xEE and 0xC8,
/// module → radio 0xC8 and 0xEA).
pub const FRAME_STARTS: [u8; 4] = [
    address::FLIGHT_CONTROLLER,
    address::RADIO,
    address::RECEIVER,
    address::TX_MODULE,
];

/// A candidate frame that failed its checks. The decoder has already resumed its search one
/// byte after the rejected start, so a real frame hidden inside is still found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejection {
    /// The length byte is outside 2…62.
    BadLength {
        /// The length byte.
        length: u8,
    },
    /// The line went idle before the frame was complete.
    Truncated {
        /// Bytes held when the line went idle.
        held: u8,
    },
    /// The CRC byte does not match type + payload.
    CrcMismatch {
        /// CRC computed over the received bytes.
        computed: u8,
        /// CRC byte received.
        received: u8,
    },
}

/// What the decoder produced.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Decoded {
    /// A frame whose CRC checked.
    Frame(Frame),
    /// A candidate frame that was thrown away.
    Rejected(Rejection),
}

/// Counters since construction.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Stats {
    /// Frames delivered.
    pub frames: u32,
    /// Candidates rejected.
    pub rejected: u32,
    /// Bytes skipped while hunting for a start byte.
    pub skipped_bytes: u32,
}

/// The streaming decoder. Holds at most one frame's worth of bytes (64).
#[derive(Debug, Clone, Default)]
pub struct Decoder {
    buffer: Vec<u8, MAX_FRAME_LEN>,
    stats: Stats,
}

impl Decoder {
    /// An empty decoder.
    pub const fn new() -> Self {
        Self {
            buffer: Vec::new(),
            stats: Stats {
                frames: 0,
                rejected: 0,
                skipped_bytes: 0,
            },
        }
    }

    /// Counters since construction.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Bytes held that do not yet form a complete frame.
    pub fn pending_len(&self) -> usize {
        self.buffer.len()
    }

    /// Forgets a partial frame (e.g. after switching the half-duplex line to transmit).
    pub fn reset(&mut self) {
        self.buffer.clear();
    }

    /// Feeds `chunk`; iterate the result to get every frame and rejection it completes. Bytes
    /// are consumed lazily: drain the iterator (see [`Feed::unconsumed`]).
    pub fn feed<'d, 'c>(&'d mut self, chunk: &'c [u8]) -> Feed<'d, 'c> {
        Feed {
            decoder: self,
            chunk,
            flushing: false,
        }
    }

    /// The UART saw the line go idle. Radios send each frame as one burst, so a partial frame
    /// held now is a false start: it is rejected and the bytes after its first byte are
    /// searched again (a real frame among them is still delivered). Drain the iterator.
    pub fn idle(&mut self) -> Feed<'_, 'static> {
        Feed {
            decoder: self,
            chunk: &[],
            flushing: true,
        }
    }

    /// Tries to take one result off the front of the buffer. Returns `None` when the buffer
    /// is empty or holds the proper prefix of a possible frame (then ≤ 63 bytes are held).
    fn parse(&mut self) -> Option<Decoded> {
        loop {
            // Hunt: drop bytes up to the next possible start.
            let start = self
                .buffer
                .iter()
                .position(|b| FRAME_STARTS.contains(b))
                .unwrap_or(self.buffer.len());
            if start > 0 {
                self.drop_front(start);
                self.stats.skipped_bytes = self.stats.skipped_bytes.saturating_add(start as u32);
            }
            let [_, length, ..] = self.buffer.as_slice() else {
                return None;
            };
            let length = *length;
            if !(MIN_LENGTH_BYTE..=MAX_LENGTH_BYTE).contains(&length) {
                self.drop_front(1);
                return Some(self.reject(Rejection::BadLength { length }));
            }
            let wire_len = usize::from(length) + 2;
            let candidate = self.buffer.get(..wire_len)?;
            let Some((received, [address, _, frame_type, payload @ ..])) = candidate.split_last()
            else {
                // A 2-byte length means at least 4 bytes here; nothing else can happen, but a
                // malformed state is treated like garbage rather than trusted.
                self.drop_front(1);
                continue;
            };
            let mut digest = FRAME_CRC.digest();
            digest.update(&[*frame_type]);
            digest.update(payload);
            let computed = digest.finalize();
            if computed != *received {
                let received = *received;
                self.drop_front(1);
                return Some(self.reject(Rejection::CrcMismatch { computed, received }));
            }
            let frame = Frame::new(*address, *frame_type, payload);
            self.drop_front(wire_len);
            match frame {
                Ok(frame) => {
                    self.stats.frames = self.stats.frames.saturating_add(1);
                    return Some(Decoded::Frame(frame));
                }
                // Cannot happen for length ≤ 62; skip rather than panic.
                Err(_) => continue,
            }
        }
    }

    fn reject(&mut self, rejection: Rejection) -> Decoded {
        self.stats.rejected = self.stats.rejected.saturating_add(1);
        Decoded::Rejected(rejection)
    }

    fn drop_front(&mut self, count: usize) {
        let count = count.min(self.buffer.len());
        self.buffer.rotate_left(count);
        self.buffer.truncate(self.buffer.len() - count);
    }

    fn accept(&mut self, byte: u8) {
        // `parse` leaves at most 63 bytes, so there is always room; if that invariant were
        // ever broken the oldest byte goes, never the new one.
        if self.buffer.is_full() {
            self.drop_front(1);
            self.stats.skipped_bytes = self.stats.skipped_bytes.saturating_add(1);
        }
        let _ = self.buffer.push(byte);
    }
}

/// Iterator over what one chunk completes. See [`Decoder::feed`].
#[derive(Debug)]
pub struct Feed<'d, 'c> {
    decoder: &'d mut Decoder,
    chunk: &'c [u8],
    /// Line idle: a held partial frame is given up instead of waited for.
    flushing: bool,
}

impl Feed<'_, '_> {
    /// Bytes of the chunk not yet taken into the decoder (empty once the iterator is drained).
    pub fn unconsumed(&self) -> &[u8] {
        self.chunk
    }
}

impl Iterator for Feed<'_, '_> {
    type Item = Decoded;

    fn next(&mut self) -> Option<Decoded> {
        loop {
            if let Some(decoded) = self.decoder.parse() {
                return Some(decoded);
            }
            let Some((&byte, rest)) = self.chunk.split_first() else {
                if self.flushing && !self.decoder.buffer.is_empty() {
                    let held = self.decoder.buffer.len().min(usize::from(u8::MAX)) as u8;
                    self.decoder.drop_front(1);
                    return Some(self.decoder.reject(Rejection::Truncated { held }));
                }
                return None;
            };
            self.chunk = rest;
            self.decoder.accept(byte);
        }
    }
}
