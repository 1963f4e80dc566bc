//! u-blox receivers over UART, UBX protocol only, sans-IO: the caller moves UART bytes in
//! and out and passes the time in; nothing here blocks, allocates or panics.
//!
//! - [`frame`]: sync, length, Fletcher checksum; a [`Parser`] with bounded memory that finds
//!   every good frame, also one hidden behind garbage or a false header;
//! - [`nav_pvt`]: the navigation solution ([`NavPvt`]), decoded and encoded;
//! - [`config`]: boot configuration for M8 and M9/M10 receivers ([`Configurator`]) with
//!   ACK/NAK follow-up, retries and a named failure.
//!
//! "UART1" in [`config`] is the *receiver's* port. What a fix is worth to an estimator is
//! the user's business (TauLink's is `flight-core`'s `GpsAiding`). The cost of parsing is
//! measured on a Cortex-M4 (the crate's README).
//!
//! ```
//! use ubx::{Message, Parser, frame};
//!
//! // An ACK-ACK of CFG-VALSET behind line noise (one a false sync byte), as a UART delivers it.
//! let mut uart = vec![0x00, 0xB5];
//! uart.extend_from_slice(&frame::encode(0x05, 0x01, &[0x06, 0x8A]).unwrap());
//! let mut parser = Parser::new();
//! let mut messages = Vec::new();
//! for chunk in uart.chunks(3) {
//!     parser.feed(chunk, |f| messages.push(Message::from_frame(&f)));
//! }
//! assert_eq!(messages, [Message::Ack { class: 0x06, id: 0x8A }]);
//! ```
#![cfg_attr(not(test), no_std)]
// docs.rs: the feature each gated item needs, shown beside it.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod config;
pub mod frame;
pub mod nav_pvt;

#[cfg(test)]
mod tests;

pub use config::{Configurator, Generation, Settings, Status};
pub use frame::{Frame, Parser};
pub use nav_pvt::{FixType, NavPvt};

/// ACK class.
pub const CLASS_ACK: u8 = 0x05;
/// ACK-ACK id.
pub const ID_ACK: u8 = 0x01;
/// ACK-NAK id.
pub const ID_NAK: u8 = 0x00;

/// A decoded frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Message {
    /// Navigation solution.
    NavPvt(NavPvt),
    /// The message `class`/`id` was accepted.
    Ack {
        /// Class of the acknowledged message.
        class: u8,
        /// Id of the acknowledged message.
        id: u8,
    },
    /// The message `class`/`id` was refused.
    Nak {
        /// Class of the refused message.
        class: u8,
        /// Id of the refused message.
        id: u8,
    },
    /// A well-framed message we do not read, or one of ours with the wrong length.
    Other {
        /// Class.
        class: u8,
        /// Id.
        id: u8,
    },
}

impl Message {
    /// Decodes a checked frame.
    #[must_use]
    pub fn from_frame(frame: &Frame<'_>) -> Self {
        let other = Self::Other {
            class: frame.class,
            id: frame.id,
        };
        match (frame.class, frame.id, frame.payload) {
            (nav_pvt::CLASS, nav_pvt::ID, p) => NavPvt::decode(p).map_or(other, Self::NavPvt),
            (CLASS_ACK, ID_ACK, &[class, id]) => Self::Ack { class, id },
            (CLASS_ACK, ID_NAK, &[class, id]) => Self::Nak { class, id },
            _ => other,
        }
    }
}
