//! PX4's ULog, the self-describing flight-log format that pyulog, PlotJuggler, PX4 Flight
//! Review and Foxglove read (specification: PX4-Autopilot `docs/en/dev_log/ulog_file_format.md`).
//!
//! - [`Writer`] appends whole messages (header, flag bits, formats, information, parameters,
//!   subscriptions, logged data and strings, synchronisation, dropouts) into a buffer the
//!   caller owns: no heap, no `core::fmt`, and a message that does not fit is refused whole
//!   ([`Error::Full`]), so a buffer only ever holds complete messages.
//! - [`record!`] declares a fixed-size logged message once: its struct, its ULog format
//!   string and its little-endian encoding and decoding ([`Record`]) come from one list.
//! - [`Reader`] walks a log's bytes as the specification asks of a parser: unknown message
//!   types are handed on as [`Message::Unknown`], a log cut in the middle of a message ends
//!   at its last whole one ([`Reader::truncated`]), unknown incompatible flags are refused;
//!   every malformed message is an [`Error`] naming its offset, never a panic.
//! - [`format`] parses format strings and information/parameter keys and reads typed
//!   values out of logged bytes.
//!
//! Every message is little endian; strings are not NUL-terminated. This crate writes file
//! version 1 with the flag-bits message (what PX4's logger writes, and what pyulog reads
//! without a warning).
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod format;
mod reader;
mod record;
mod writer;

pub use format::{Basic, Key, Scalar, TypeRef};
pub use reader::{Header, Message, Reader};
pub use record::{Field, Record};
pub use writer::Writer;

/// The file's first seven bytes: "ULog" and 0x01 0x12 0x35.
pub const MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];
/// The file format version written.
pub const VERSION: u8 = 1;
/// Length of the file header: magic, version, start timestamp.
pub const HEADER_LEN: usize = 16;
/// Length of every message's header: `u16` size of the body, `u8` type.
pub const MESSAGE_HEADER_LEN: usize = 3;
/// The synchronisation message's body.
pub const SYNC_MAGIC: [u8; 8] = [0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12];
/// Body length of the flag-bits message this crate writes (compat, incompat, 3 offsets).
pub const FLAG_BITS_LEN: usize = 40;

/// The message types (`msg_type`), by their letters.
pub mod kind {
    /// Flag bits: must follow the header.
    pub const FLAG_BITS: u8 = b'B';
    /// Format definition.
    pub const FORMAT: u8 = b'F';
    /// Information (key: value).
    pub const INFO: u8 = b'I';
    /// Multi information.
    pub const INFO_MULTIPLE: u8 = b'M';
    /// Parameter value.
    pub const PARAMETER: u8 = b'P';
    /// Default parameter value.
    pub const PARAMETER_DEFAULT: u8 = b'Q';
    /// Subscription: a message id for a format.
    pub const SUBSCRIPTION: u8 = b'A';
    /// Unsubscription.
    pub const UNSUBSCRIPTION: u8 = b'R';
    /// Logged data.
    pub const DATA: u8 = b'D';
    /// Logged string.
    pub const LOGGING: u8 = b'L';
    /// Tagged logged string.
    pub const LOGGING_TAGGED: u8 = b'C';
    /// Synchronisation.
    pub const SYNC: u8 = b'S';
    /// Dropout mark.
    pub const DROPOUT: u8 = b'O';
}

/// Log levels of logged strings (as the Linux kernel's, ASCII digits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Level {
    /// System is unusable.
    Emergency = b'0',
    /// Action must be taken immediately.
    Alert = b'1',
    /// Critical conditions.
    Critical = b'2',
    /// Error conditions.
    Error = b'3',
    /// Warning conditions.
    Warning = b'4',
    /// Normal but significant.
    Notice = b'5',
    /// Informational.
    Info = b'6',
    /// Debug-level.
    Debug = b'7',
}

/// Why a message could not be written or read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error {
    /// The writer's buffer has no room for the whole message (nothing was written).
    Full,
    /// The message body would exceed the 65 535 bytes a message header can state.
    TooLong,
    /// A name, key or format holds characters or a shape the specification does not allow.
    InvalidText,
    /// Not a ULog file: the magic does not match, or the header is shorter than 16 bytes.
    NotULog,
    /// The log sets an incompatible flag this reader does not know: it must not be read.
    IncompatibleFlags,
    /// The message at this offset is too short for its type, or its text is not UTF-8.
    Malformed {
        /// File offset of the message's header.
        offset: usize,
    },
    /// A field's bytes are not what its record expects (wrong length, or a different
    /// format string).
    Layout,
    /// The format names a nested type (this reader reads basic types only).
    Nested,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Full => f.write_str("no room for the whole message"),
            Error::TooLong => f.write_str("message longer than 65535 bytes"),
            Error::InvalidText => f.write_str("invalid name, key or format text"),
            Error::NotULog => f.write_str("not a ULog file (bad magic or short header)"),
            Error::IncompatibleFlags => f.write_str("unknown incompatible flags set"),
            Error::Malformed { offset } => write!(f, "malformed message at offset {offset}"),
            Error::Layout => f.write_str("data does not match the record's layout"),
            Error::Nested => f.write_str("nested types are not supported"),
        }
    }
}

impl core::error::Error for Error {}

/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
