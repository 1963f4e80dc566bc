//! CRSF ("Crossfire") between the radio and the module on the JR bay's half-duplex S.Port
//! pin: frames, a streaming decoder, typed messages and the module's reply logic
//! (the CRSF protocol as ExpressLRS and EdgeTX implement it).
//!
//! The module's receive loop (decoder → responder → reply in the line's idle gap) is the
//! first example of the [crate] documentation.

pub mod channels;
pub mod decoder;
pub mod device;
pub mod frame;
mod from_report;
pub mod message;
pub mod params;
pub mod responder;
pub mod sensors;

pub use channels::RcChannels;
pub use decoder::{Decoded, Decoder, Rejection};
pub use device::{BindCommand, DeviceInfo, DevicePing, ModelSelect, TimingCorrection};
pub use frame::{Error, Frame, address, frame_type};
pub use message::Message;
pub use responder::Responder;
pub use sensors::{Attitude, BaroAltitude, Battery, FlightModeFrame, Gps, LinkStatistics, Vario};
