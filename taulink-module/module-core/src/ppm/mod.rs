//! PPM on the JR bay: the decoder for the handset's PPM (transmitter role) and the generator
//! for the receiver role's PPM output (protocols.md §2).

pub mod decoder;
pub mod encoder;
#[cfg(test)]
pub(crate) mod waveform;

pub use decoder::{Decoded, Decoder, DecoderConfig, Lost, Reject};
pub use encoder::{Encoder, EncoderConfig, FailsafeOutput, Frame, Slot};
