//! CRSF ("Crossfire") between the radio and the module on the JR bay's half-duplex S.Port
//! pin: frames, a streaming decoder, typed messages and the module's reply logic
//! (the CRSF protocol as ExpressLRS and EdgeTX implement it).
//!
//! The module's receive loop, with the UART and clock left to the caller:
//!
//! ```
//! use telemetry::handset::HandsetTelemetry;
//! use telemetry::handset::crsf::responder::{Config, Responder, taulink_device_info};
//! use telemetry::handset::crsf::{Decoded, Decoder, Message};
//!
//! let mut decoder = Decoder::new();
//! let mut responder = Responder::new(Config::new(400_000, taulink_device_info(0, 1, 0)));
//! let telemetry = HandsetTelemetry::default();
//!
//! // EdgeTX ≥ 2.11 pings before it sends channels.
//! let received = [0xC8, 0x04, 0x28, 0x00, 0xEA, 0x54];
//! let now_us = 1_000;
//! for decoded in decoder.feed(&received) {
//!     if let Decoded::Frame(frame) = decoded {
//!         if let Some(Message::RcChannels(channels)) = responder.on_frame(now_us, &frame) {
//!             let _pulse_widths_us = channels.to_us(); // to the link
//!         }
//!     }
//! }
//! // Line idle after the radio's frame: our turn to talk.
//! let mut reply = [0u8; 128];
//! let len = responder.reply(now_us + 20, &telemetry, &mut reply).unwrap().len();
//! assert_eq!(&reply[..3], &[0xC8, 0x1A, 0x29]); // DEVICE_INFO first
//! assert!(len > 28); // then LINK_STATISTICS (LQ 0: no link yet)
//! ```

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
