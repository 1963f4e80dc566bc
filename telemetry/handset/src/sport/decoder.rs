//! Streaming S.Port decoder. A 0x7E always starts a frame (even mid-frame or after an
//! escape), so a real frame is never lost to garbage before it.

use super::{Frame, START, STUFF, STUFF_XOR, checksum};

/// A candidate frame that failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejection {
    /// A new 0x7E came before 8 bytes were collected.
    Truncated {
        /// Bytes after the physical ID collected before the restart.
        held: u8,
    },
    /// 0x7D where the physical ID belongs: no sensor has it (IDs carry parity bits), and the
    /// encoder could not send it back.
    ReservedPhysicalId,
    /// The checksum over the 8 unstuffed bytes did not fold to 0xFF.
    CrcMismatch {
        /// CRC computed over the 7 body bytes.
        computed: u8,
        /// CRC byte received.
        received: u8,
    },
}

/// What one byte completed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// A frame whose checksum held.
    Frame(Frame),
    /// `7E physId` followed by a new `7E`: a master polled that ID and nobody answered.
    Poll {
        /// The polled physical ID.
        physical_id: u8,
    },
    /// A candidate thrown away.
    Rejected(Rejection),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Waiting for 0x7E.
    Hunting,
    /// Got 0x7E, next byte is the physical ID.
    Started,
    /// Collecting the 8 bytes after the physical ID.
    Body {
        physical_id: u8,
        bytes: [u8; 8],
        held: u8,
        escaped: bool,
    },
}

/// The decoder: 11 bytes of state, one event per byte at most.
#[derive(Debug, Clone)]
pub struct Decoder {
    state: State,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder hunting for 0x7E.
    pub const fn new() -> Self {
        Self {
            state: State::Hunting,
        }
    }

    /// Takes one byte from the line.
    pub fn push(&mut self, byte: u8) -> Option<Event> {
        if byte == START {
            let event = match self.state {
                State::Body {
                    held: 0,
                    physical_id,
                    ..
                } => Some(Event::Poll { physical_id }),
                State::Body { held, .. } => Some(Event::Rejected(Rejection::Truncated { held })),
                State::Hunting | State::Started => None,
            };
            self.state = State::Started;
            return event;
        }
        match &mut self.state {
            State::Hunting => None,
            State::Started if byte == STUFF => {
                self.state = State::Hunting;
                Some(Event::Rejected(Rejection::ReservedPhysicalId))
            }
            State::Started => {
                self.state = State::Body {
                    physical_id: byte,
                    bytes: [0; 8],
                    held: 0,
                    escaped: false,
                };
                None
            }
            State::Body {
                physical_id,
                bytes,
                held,
                escaped,
            } => {
                if byte == STUFF && !*escaped {
                    *escaped = true;
                    return None;
                }
                let value = if *escaped { byte ^ STUFF_XOR } else { byte };
                *escaped = false;
                if let Some(slot) = bytes.get_mut(usize::from(*held)) {
                    *slot = value;
                }
                *held += 1;
                if usize::from(*held) < bytes.len() {
                    return None;
                }
                let physical_id = *physical_id;
                let [primitive, i0, i1, v0, v1, v2, v3, received] = *bytes;
                self.state = State::Hunting;
                let frame = Frame {
                    physical_id,
                    primitive,
                    value_id: u16::from_le_bytes([i0, i1]),
                    value: u32::from_le_bytes([v0, v1, v2, v3]),
                };
                let computed = checksum(&frame.body());
                Some(if computed == received {
                    Event::Frame(frame)
                } else {
                    Event::Rejected(Rejection::CrcMismatch { computed, received })
                })
            }
        }
    }

    /// Takes a chunk; `on_event` sees every event in order.
    pub fn push_all(&mut self, bytes: &[u8], mut on_event: impl FnMut(Event)) {
        for &byte in bytes {
            if let Some(event) = self.push(byte) {
                on_event(event);
            }
        }
    }
}
