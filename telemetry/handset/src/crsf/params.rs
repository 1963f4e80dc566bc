//! The CRSF parameter protocol, as the ExpressLRS Lua script (`elrsV3.lua`, which EdgeTX users
//! run as the "ExpressLRS" tool for any CRSF module) and EdgeTX speak it: the radio reads a
//! parameter's description chunk by chunk (PARAMETER_READ 0x2C → PARAMETER_SETTINGS_ENTRY
//! 0x2B), writes a value (PARAMETER_WRITE 0x2D) and steps a command through its
//! status/timeout handshake. This module owns the wire format only; what the parameters are
//! belongs to the device (`module_core::params`).
//!
//! A parameter's description ("entry") is `parent, type (bit 7 = hidden), name NUL,
//! type-specific fields`; it travels in chunks, each frame carrying `destination, origin,
//! parameter number, chunks remaining` and the next piece. The radio asks for chunk 0, 1, …
//! until a frame says 0 chunks remain. Field layouts (big-endian numbers):
//!
//! * text selection (9): `options separated by ';' NUL, value, min, max, default, unit NUL`
//! * unsigned 16 (2): `value, min, max, default (u16 each), unit NUL`
//! * float (8): `value, min, max, default (i32 each, the number × 10^precision), precision
//!   (u8, decimals shown; the Lua script shows at most 3), step (u32, in the same scaled
//!   units), unit NUL`
//! * string (10): `text NUL, max length (u8)`; the radio's write carries the text NUL-terminated
//! * folder (11): nothing after the name (the children name their parent)
//! * info (12): `text NUL`
//! * command (13): `status, timeout (10 ms units: how often the radio polls), info NUL`
//!
//! A command runs: the radio writes status 1 (start); the module answers with the entry
//! (status 2 "running", or 3 "confirm?"); the radio polls with status 6 every timeout, writes 4
//! to confirm or 5 to cancel; status 0 with an info text ends it ("Stopped!" popup).

use heapless::Vec;

use super::frame::{Error, MAX_PAYLOAD_LEN, frame_type};

/// Bytes of a parameter chunk frame's payload before the data: destination, origin, number,
/// chunks remaining.
pub const CHUNK_HEADER_LEN: usize = 4;
/// Most data one chunk frame carries.
pub const MAX_CHUNK_DATA: usize = MAX_PAYLOAD_LEN - CHUNK_HEADER_LEN;
/// Longest parameter description this module builds.
pub const MAX_ENTRY_LEN: usize = 256;
/// Longest value a write carries (a string parameter).
pub const MAX_WRITE_LEN: usize = MAX_PAYLOAD_LEN - 3;

/// Parameter types (the Lua script's numbering).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum ParameterType {
    /// Unsigned 8-bit number.
    Uint8 = 0,
    /// Unsigned 16-bit number.
    Uint16 = 2,
    /// A fixed-point number: an `i32` scaled by 10^precision.
    Float = 8,
    /// One of a list of texts.
    TextSelection = 9,
    /// Text.
    String = 10,
    /// A folder the children name as parent.
    Folder = 11,
    /// Read-only text.
    Info = 12,
    /// An action with a status handshake.
    Command = 13,
}

/// A command's state (the `status` byte of a command entry, and what the radio writes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum CommandStatus {
    /// Idle, or finished (with an info text).
    Ready = 0,
    /// Radio → module: run it.
    Start = 1,
    /// Running.
    Progress = 2,
    /// The module asks the pilot to confirm.
    ConfirmationNeeded = 3,
    /// Radio → module: confirmed.
    Confirm = 4,
    /// Radio → module: cancelled.
    Cancel = 5,
    /// Radio → module: how is it going (answer with the entry).
    Poll = 6,
}

impl CommandStatus {
    /// The status for a written byte.
    pub const fn from_byte(byte: u8) -> Option<Self> {
        Some(match byte {
            0 => Self::Ready,
            1 => Self::Start,
            2 => Self::Progress,
            3 => Self::ConfirmationNeeded,
            4 => Self::Confirm,
            5 => Self::Cancel,
            6 => Self::Poll,
            _ => return None,
        })
    }
}

/// PARAMETER_READ (0x2C): the radio asks for chunk `chunk` of parameter `number`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParameterRead {
    /// Addressee (0xEE, the module).
    pub destination: u8,
    /// Sender (0xEA radio, 0xEF the ExpressLRS Lua).
    pub origin: u8,
    /// Parameter number (1 … count; 0 is the root folder).
    pub number: u8,
    /// Chunk index.
    pub chunk: u8,
}

impl ParameterRead {
    /// The 4-byte payload.
    pub fn to_payload(&self) -> [u8; 4] {
        [self.destination, self.origin, self.number, self.chunk]
    }

    /// Reads the payload.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        match payload {
            [destination, origin, number, chunk] => Ok(Self {
                destination: *destination,
                origin: *origin,
                number: *number,
                chunk: *chunk,
            }),
            _ => Err(Error::PayloadLength {
                frame_type: frame_type::PARAMETER_READ,
                length: payload.len(),
            }),
        }
    }
}

/// PARAMETER_WRITE (0x2D): the radio sets parameter `number` to `value` (one byte for a
/// selection or a command step, big-endian for numbers, NUL-terminated for text).
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParameterWrite {
    /// Addressee (0xEE).
    pub destination: u8,
    /// Sender.
    pub origin: u8,
    /// Parameter number.
    pub number: u8,
    /// The value bytes.
    pub value: Vec<u8, MAX_WRITE_LEN>,
}

impl ParameterWrite {
    /// The payload.
    pub fn to_payload(&self) -> Vec<u8, MAX_PAYLOAD_LEN> {
        let mut payload = Vec::new();
        // 3 + MAX_WRITE_LEN = MAX_PAYLOAD_LEN: always fits.
        let _ = payload.extend_from_slice(&[self.destination, self.origin, self.number]);
        let _ = payload.extend_from_slice(&self.value);
        payload
    }

    /// Reads the payload (a write carries at least one value byte).
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        match payload {
            [destination, origin, number, value @ ..] if !value.is_empty() => Ok(Self {
                destination: *destination,
                origin: *origin,
                number: *number,
                value: Vec::from_slice(value).map_err(|_| Error::PayloadTooLong {
                    length: payload.len(),
                })?,
            }),
            _ => Err(Error::PayloadLength {
                frame_type: frame_type::PARAMETER_WRITE,
                length: payload.len(),
            }),
        }
    }
}

/// PARAMETER_SETTINGS_ENTRY (0x2B): one chunk of a parameter's description.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParameterChunk {
    /// Addressee (the reader's origin).
    pub destination: u8,
    /// Sender (0xEE).
    pub origin: u8,
    /// Parameter number.
    pub number: u8,
    /// Chunks after this one.
    pub chunks_remaining: u8,
    /// This chunk's part of the description.
    pub data: Vec<u8, MAX_CHUNK_DATA>,
}

impl ParameterChunk {
    /// Chunk `index` of `entry` cut into pieces of `chunk_len` bytes (1 …
    /// [`MAX_CHUNK_DATA`]); `None` past the last chunk.
    pub fn of_entry(
        entry: &[u8],
        chunk_len: usize,
        index: u8,
        number: u8,
        destination: u8,
        origin: u8,
    ) -> Option<Self> {
        let chunk_len = chunk_len.clamp(1, MAX_CHUNK_DATA);
        let chunks = entry.len().div_ceil(chunk_len).max(1);
        let index = usize::from(index);
        if index >= chunks {
            return None;
        }
        let start = index * chunk_len;
        let end = (start + chunk_len).min(entry.len());
        Some(Self {
            destination,
            origin,
            number,
            chunks_remaining: u8::try_from(chunks - 1 - index).ok()?,
            data: Vec::from_slice(entry.get(start..end)?).ok()?,
        })
    }

    /// The payload.
    pub fn to_payload(&self) -> Vec<u8, MAX_PAYLOAD_LEN> {
        let mut payload = Vec::new();
        let _ = payload.extend_from_slice(&[
            self.destination,
            self.origin,
            self.number,
            self.chunks_remaining,
        ]);
        let _ = payload.extend_from_slice(&self.data);
        payload
    }

    /// Reads the payload.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        match payload {
            [destination, origin, number, chunks_remaining, data @ ..] => Ok(Self {
                destination: *destination,
                origin: *origin,
                number: *number,
                chunks_remaining: *chunks_remaining,
                data: Vec::from_slice(data).map_err(|_| Error::PayloadTooLong {
                    length: payload.len(),
                })?,
            }),
            _ => Err(Error::PayloadLength {
                frame_type: frame_type::PARAMETER_SETTINGS_ENTRY,
                length: payload.len(),
            }),
        }
    }
}

/// Builds one parameter description; an entry that would overflow [`MAX_ENTRY_LEN`] is an
/// error at [`Entry::finish`], never a truncated entry.
#[derive(Debug, Clone, Default)]
pub struct Entry {
    bytes: Vec<u8, MAX_ENTRY_LEN>,
    overflow: bool,
}

impl Entry {
    fn start(parent: u8, kind: ParameterType, name: &str) -> Self {
        let mut entry = Self::default();
        entry.push(&[parent, kind as u8]);
        entry.text(name);
        entry
    }

    fn push(&mut self, bytes: &[u8]) {
        if self.bytes.extend_from_slice(bytes).is_err() {
            self.overflow = true;
        }
    }

    fn text(&mut self, text: &str) {
        self.push(text.as_bytes());
        self.push(&[0]);
    }

    /// A text selection: `options` (each without ';'), `value` the chosen index.
    pub fn selection(
        parent: u8,
        name: &str,
        options: &[&str],
        value: u8,
        default: u8,
        unit: &str,
    ) -> Self {
        let mut entry = Self::start(parent, ParameterType::TextSelection, name);
        for (index, option) in options.iter().enumerate() {
            if index > 0 {
                entry.push(b";");
            }
            entry.push(option.as_bytes());
        }
        entry.push(&[0]);
        let max = u8::try_from(options.len().saturating_sub(1)).unwrap_or(u8::MAX);
        entry.push(&[value, 0, max, default]);
        entry.text(unit);
        entry
    }

    /// An unsigned 16-bit number within `min..=max`.
    pub fn uint16(
        parent: u8,
        name: &str,
        value: u16,
        min: u16,
        max: u16,
        default: u16,
        unit: &str,
    ) -> Self {
        let mut entry = Self::start(parent, ParameterType::Uint16, name);
        for number in [value, min, max, default] {
            entry.push(&number.to_be_bytes());
        }
        entry.text(unit);
        entry
    }

    /// A fixed-point number: every field is the number × 10^`precision` (`value`,
    /// `min..=max`, `default`); the radio steps it by `step` scaled units.
    #[allow(clippy::too_many_arguments)] // the wire entry's fields, in its order
    pub fn float(
        parent: u8,
        name: &str,
        value: i32,
        range: (i32, i32),
        default: i32,
        precision: u8,
        step: u32,
        unit: &str,
    ) -> Self {
        let mut entry = Self::start(parent, ParameterType::Float, name);
        for number in [value, range.0, range.1, default] {
            entry.push(&number.to_be_bytes());
        }
        entry.push(&[precision]);
        entry.push(&step.to_be_bytes());
        entry.text(unit);
        entry
    }

    /// This entry with the hidden flag (bit 7 of the type byte): the radio skips the row.
    pub fn hidden(mut self) -> Self {
        if let Some(kind) = self.bytes.get_mut(1) {
            *kind |= 0x80;
        }
        self
    }

    /// Editable text `value` of at most `max_len` bytes (the radio's editor stops there and
    /// its write carries the text NUL-terminated).
    pub fn string(parent: u8, name: &str, value: &str, max_len: u8) -> Self {
        let mut entry = Self::start(parent, ParameterType::String, name);
        entry.text(value);
        entry.push(&[max_len]);
        entry
    }

    /// A folder.
    pub fn folder(parent: u8, name: &str) -> Self {
        Self::start(parent, ParameterType::Folder, name)
    }

    /// Read-only text.
    pub fn info(parent: u8, name: &str, text: &str) -> Self {
        let mut entry = Self::start(parent, ParameterType::Info, name);
        entry.text(text);
        entry
    }

    /// A command in `status`; the radio polls every `timeout_10ms` × 10 ms while it runs.
    pub fn command(
        parent: u8,
        name: &str,
        status: CommandStatus,
        timeout_10ms: u8,
        info: &str,
    ) -> Self {
        let mut entry = Self::start(parent, ParameterType::Command, name);
        entry.push(&[status as u8, timeout_10ms]);
        entry.text(info);
        entry
    }

    /// The description bytes.
    pub fn finish(self) -> Result<Vec<u8, MAX_ENTRY_LEN>, Error> {
        if self.overflow {
            Err(Error::PayloadTooLong {
                length: MAX_ENTRY_LEN + 1,
            })
        } else {
            Ok(self.bytes)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_have_the_lua_layouts() {
        let selection = Entry::selection(0, "Rate", &["A", "BC"], 1, 0, "Hz")
            .finish()
            .unwrap();
        assert_eq!(
            selection.as_slice(),
            b"\x00\x09Rate\x00A;BC\x00\x01\x00\x01\x00Hz\x00"
        );
        let number = Entry::uint16(3, "T", 500, 100, 2000, 500, "ms")
            .finish()
            .unwrap();
        assert_eq!(
            number.as_slice(),
            b"\x03\x02T\x00\x01\xF4\x00\x64\x07\xD0\x01\xF4ms\x00"
        );
        let string = Entry::string(0, "Phrase", "", 56).finish().unwrap();
        assert_eq!(string.as_slice(), b"\x00\x0APhrase\x00\x00\x38");
        let command = Entry::command(0, "Bind", CommandStatus::Progress, 50, "Binding")
            .finish()
            .unwrap();
        assert_eq!(command.as_slice(), b"\x00\x0DBind\x00\x02\x32Binding\x00");
        let long = "x".repeat(300);
        assert!(Entry::folder(0, &long).finish().is_err());
    }

    #[test]
    fn a_float_entry_is_the_lua_scripts_layout() {
        // −1.25 in −10.00 … 10.00, default 0, 2 decimals, step 0.05: value, min, max and
        // default at +0/+4/+8/+12, precision at +16, step at +17, unit at +21 after the name.
        let float = Entry::float(2, "K", -125, (-1000, 1000), 0, 2, 5, "s")
            .finish()
            .unwrap();
        assert_eq!(
            float.as_slice(),
            b"\x02\x08K\x00\xFF\xFF\xFF\x83\xFF\xFF\xFC\x18\x00\x00\x03\xE8\x00\x00\x00\x00\x02\x00\x00\x00\x05s\x00"
        );
        let hidden = Entry::folder(0, "VTX").hidden().finish().unwrap();
        assert_eq!(hidden.as_slice(), b"\x00\x8BVTX\x00");
    }

    #[test]
    fn chunks_cover_the_entry_and_count_down() {
        let entry: std::vec::Vec<u8> = (0..100).collect();
        let chunks: std::vec::Vec<ParameterChunk> = (0..)
            .map_while(|i| ParameterChunk::of_entry(&entry, 40, i, 7, 0xEA, 0xEE))
            .collect();
        assert_eq!(chunks.len(), 3);
        assert_eq!(
            chunks
                .iter()
                .map(|c| c.chunks_remaining)
                .collect::<std::vec::Vec<_>>(),
            [2, 1, 0]
        );
        let joined: std::vec::Vec<u8> = chunks.iter().flat_map(|c| c.data.clone()).collect();
        assert_eq!(joined, entry);
        let payload = chunks[1].to_payload();
        assert_eq!(&payload[..4], &[0xEA, 0xEE, 7, 1]);
        assert_eq!(ParameterChunk::from_payload(&payload).unwrap(), chunks[1]);
    }

    #[test]
    fn reads_and_writes_parse() {
        assert_eq!(
            ParameterRead::from_payload(&[0xEE, 0xEA, 3, 1]),
            Ok(ParameterRead {
                destination: 0xEE,
                origin: 0xEA,
                number: 3,
                chunk: 1
            })
        );
        assert!(ParameterRead::from_payload(&[0xEE, 0xEA, 3]).is_err());
        // Worked frame K (`tests/crsf_frames.rs`): `C8 06 2D EE EF 11 01 A5`, a parameter
        // write published in other CRSF parsers' tests.
        let write = ParameterWrite::from_payload(&[0xEE, 0xEF, 0x11, 0x01]).unwrap();
        assert_eq!((write.number, write.value.as_slice()), (0x11, &[1u8][..]));
        assert!(ParameterWrite::from_payload(&[0xEE, 0xEF, 0x11]).is_err());
    }
}
