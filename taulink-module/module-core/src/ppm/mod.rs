//! PPM on the JR bay: the decoder for the handset's PPM (transmitter role) and the generator
//! for the receiver role's PPM output. Timing as EdgeTX generates it (`radio/src/pulses/ppm.cpp`):
//! 0.5 µs steps, 22.5 ms frames for 8 channels (+2 ms per channel above 8), 300 µs pulses,
//! 988…2012 µs at ±100 %.

pub mod decoder;
pub mod encoder;
#[cfg(test)]
pub(crate) mod waveform;

pub use decoder::{Decoded, Decoder, DecoderConfig, Lost, Reject};
pub use encoder::{Encoder, EncoderConfig, FailsafeOutput, Frame, Slot};
