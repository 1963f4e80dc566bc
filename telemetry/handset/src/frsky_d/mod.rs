//! FrSky D ("hub") telemetry at 9600 Bd as openLRSng's TX sends it to the radio: 0x7E-framed
//! link frames (0xFE: A1, A2, RSSI) and user frames (0xFD: up to 6 hub-stream bytes), with
//! 0x7D stuffing (EdgeTX `frsky_d.cpp`).

use core::fmt;

use super::stuffing::{self, Writer, stuffed_len};

use heapless::Vec;

pub mod hub;

pub use hub::{HubDecoder, HubRecord, Sender};

/// Frame delimiter (before and after every frame).
pub const DELIMITER: u8 = stuffing::FRAME;
/// Escape byte: the next byte was XORed with [`STUFF_XOR`].
pub const STUFF: u8 = stuffing::ESCAPE;
/// XOR applied to an escaped byte.
pub const STUFF_XOR: u8 = stuffing::ESCAPE_XOR;
/// Type byte of a link frame.
pub const LINK_FRAME: u8 = 0xFE;
/// Type byte of a user-data frame.
pub const USER_FRAME: u8 = 0xFD;
/// Hub bytes one user frame carries.
pub const USER_DATA_MAX: usize = 6;
/// Unstuffed bytes between the delimiters: type + 8.
pub const FRAME_LEN: usize = 9;
/// Longest frame on the wire: two delimiters, type, 8 bytes that may each be escaped.
pub const MAX_WIRE_LEN: usize = 3 + 2 * 8;

/// Why a frame could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The output buffer is shorter than the stuffed frame.
    BufferTooSmall {
        /// Bytes the frame needs.
        needed: usize,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BufferTooSmall { needed } => write!(f, "buffer too small, need {needed} bytes"),
        }
    }
}

impl core::error::Error for Error {}

/// Link frame 0xFE. EdgeTX shows A1/A2 as volts (raw · 13.2 / 255 by default) and uses RSSI
/// as its RSSI and streaming heartbeat; openLRSng sends its 0…255 RSSI halved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkFrame {
    /// Analog 1, raw 0…255.
    pub a1: u8,
    /// Analog 2, raw 0…255.
    pub a2: u8,
    /// RSSI at the receiving end of the downlink (0…127 in FrSky practice).
    pub rssi: u8,
    /// RSSI of the uplink as seen by the receiver.
    pub tx_rssi: u8,
}

/// One FrSky D frame.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Frame {
    /// 0xFE.
    Link(LinkFrame),
    /// 0xFD with 0…6 hub-stream bytes.
    User(Vec<u8, USER_DATA_MAX>),
}

impl Frame {
    /// The 9 unstuffed bytes between the delimiters; user frames are padded with zeros.
    pub fn bytes(&self) -> [u8; FRAME_LEN] {
        match self {
            Self::Link(link) => [
                LINK_FRAME,
                link.a1,
                link.a2,
                link.rssi,
                link.tx_rssi,
                0,
                0,
                0,
                0,
            ],
            Self::User(data) => {
                let mut out = [USER_FRAME, data.len() as u8, 0, 0, 0, 0, 0, 0, 0];
                for (slot, &byte) in out.iter_mut().skip(3).zip(data.iter()) {
                    *slot = byte;
                }
                out
            }
        }
    }

    /// Writes `7E`, the stuffed frame and `7E`; returns the bytes written (11…19).
    pub fn encode<'o>(&self, out: &'o mut [u8]) -> Result<&'o [u8], Error> {
        let bytes = self.bytes();
        let needed = 2 + stuffed_len(bytes);
        let Some(out) = out.get_mut(..needed) else {
            return Err(Error::BufferTooSmall { needed });
        };
        let mut w = Writer::new(&mut *out);
        w.raw(DELIMITER);
        for byte in bytes {
            w.stuffed(byte);
        }
        w.raw(DELIMITER);
        Ok(out)
    }
}

/// A candidate frame that was thrown away (FrSky D has no checksum: only shape is checked).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejection {
    /// A delimiter came before 9 bytes were collected.
    Truncated {
        /// Bytes collected.
        held: u8,
    },
    /// The type byte is neither 0xFE nor 0xFD.
    UnknownType {
        /// The type byte.
        frame_type: u8,
    },
    /// A user frame claims more than 6 bytes.
    BadUserLength {
        /// The claimed count.
        length: u8,
    },
}

/// What one byte completed.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// A frame of a known shape.
    Frame(Frame),
    /// A candidate thrown away.
    Rejected(Rejection),
}

/// Streaming decoder: a delimiter always (re)starts a frame; 9 unstuffed bytes complete it.
#[derive(Debug, Clone, Default)]
pub struct Decoder {
    bytes: [u8; FRAME_LEN],
    /// `None` while hunting for a delimiter.
    held: Option<u8>,
    escaped: bool,
}

impl Decoder {
    /// A decoder hunting for 0x7E.
    pub const fn new() -> Self {
        Self {
            bytes: [0; FRAME_LEN],
            held: None,
            escaped: false,
        }
    }

    /// Takes one byte from the line.
    pub fn push(&mut self, byte: u8) -> Option<Event> {
        if byte == DELIMITER {
            let truncated = self.held.filter(|&held| held > 0);
            self.held = Some(0);
            self.escaped = false;
            return truncated.map(|held| Event::Rejected(Rejection::Truncated { held }));
        }
        let held = self.held?;
        if byte == STUFF && !self.escaped {
            self.escaped = true;
            return None;
        }
        let value = if self.escaped { byte ^ STUFF_XOR } else { byte };
        self.escaped = false;
        if let Some(slot) = self.bytes.get_mut(usize::from(held)) {
            *slot = value;
        }
        let held = held + 1;
        if usize::from(held) < FRAME_LEN {
            self.held = Some(held);
            return None;
        }
        self.held = None;
        Some(parse(&self.bytes))
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

fn parse(bytes: &[u8; FRAME_LEN]) -> Event {
    let [frame_type, b1, b2, b3, b4, ..] = *bytes;
    match frame_type {
        LINK_FRAME => Event::Frame(Frame::Link(LinkFrame {
            a1: b1,
            a2: b2,
            rssi: b3,
            tx_rssi: b4,
        })),
        USER_FRAME => {
            let length = b1;
            // The user data's Vec holds at most USER_DATA_MAX: a longer claim is refused by
            // the type, never cut to an empty frame.
            match bytes
                .get(3..3 + usize::from(length))
                .and_then(|data| Vec::from_slice(data).ok())
            {
                Some(data) => Event::Frame(Frame::User(data)),
                None => Event::Rejected(Rejection::BadUserLength { length }),
            }
        }
        frame_type => Event::Rejected(Rejection::UnknownType { frame_type }),
    }
}
