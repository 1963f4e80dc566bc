//! CRSF ("Crossfire") between the radio and the module on the JR bay's half-duplex S.Port
//! pin: frames, a streaming decoder, typed messages and the module's reply logic
//! (protocols.md §4).

pub mod channels;
pub mod decoder;
pub mod device;
pub mod frame;
mod from_report;
pub mod message;
pub mod responder;
pub mod sensors;

pub use channels::RcChannels;
pub use decoder::{Decoded, Decoder, Rejection};
pub use device::{DeviceInfo, DevicePing, ModelSelect, TimingCorrection};
pub use frame::{Error, Frame, address, frame_type};
pub use message::Message;
pub use responder::Responder;
pub use sensors::{Attitude, Battery, FlightMode, Gps, LinkStatistics};
