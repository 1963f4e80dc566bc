//! u-blox receiver over UART, UBX protocol only: [`frame`] (sync, length, Fletcher
//! checksum; a parser that never panics and finds every good frame), [`nav_pvt`] (the
//! navigation solution), [`config`] (boot configuration for M8 and M9/M10 with ACK/NAK
//! follow-up). Sans-IO: the firmware moves UART bytes in and out; the estimator side of a
//! fix is [`crate::estimation::ins::aiding::gps::GpsAiding`]. On the Sparky2 the receiver
//! plugs into the Main port (USART1, PA9 TX / PA10 RX) or the Flexi port (USART3, PB10 /
//! PB11), as `hardware/brushedsparky/README.md` lists; "UART1" in [`config`] is the *receiver's*
//! port.
//!
//! Cost (m4count, `tests/m4-bench` `gps`): one 100-byte NAV-PVT through [`Parser`] and
//! [`Message::from_frame`] is 4,241 Cortex-M4 instructions (~42 per byte); at 10 Hz that is
//! 42 k instructions per second, 0.03 % of a 168 MHz F405 at ~1.2 cycles per instruction.

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
