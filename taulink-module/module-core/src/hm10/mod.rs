//! The HM-10 BLE bridge to a phone ground station (JNHuaMao HM-10, HMSoft firmware;
//! GATT service 0xFFE0, characteristic 0xFFE1, 20-byte notifications): boot-time AT
//! configuration, and the relay of telemetry records both ways over its transparent UART.
//!
//! ## Framing on the phone side
//! The HM-10 chops its UART stream into ≤ 20-byte BLE notifications at arbitrary points, so
//! the stream carries its own frames: every record (one telemetry record as the link hands
//! it to the module, or one record from the phone for the flight side) is COBS-encoded
//! ([`telemetry::cobs`], the same COBS as the telemetry stream's framing) and followed by a
//! single 0x00. A reader resynchronises at the next 0x00 after any loss. Drops always remove
//! whole records, never parts of one.

pub mod at;
pub mod queue;
pub mod relay;

pub use at::{Action, Configurator, Outcome};
pub use queue::{Pushed, RecordQueue};
pub use relay::{PhoneEvent, Relay};
