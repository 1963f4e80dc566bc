//! The telemetry stream to JSON: `telemetry::messages::MessageReader` over any chunking of
//! the byte stream, each decoded message serialised with serde as the Rust type describes
//! it (`{"Battery":{"voltage_mv":11870,...}}`, `{"FlightMode":"AltitudeHold"}`), each
//! dropped frame as the string `"Dropped"`. The HM-10 relay's frames are the link frames
//! byte for byte (module-core `records`), so the same reader serves the phone, the flight
//! USB console and the simulator.

use telemetry::messages::{Decoded, MessageReader};

/// Decodes a byte stream into JSON events; bounded by the reader (one frame).
#[derive(Debug, Default)]
pub struct StreamDecoder {
    reader: MessageReader,
    dropped: u32,
}

impl StreamDecoder {
    /// A decoder waiting for the first delimiter.
    pub fn new() -> Self {
        Self::default()
    }

    /// Decodes `bytes`; returns a JSON array of the events they completed, in order.
    pub fn push(&mut self, bytes: &[u8]) -> String {
        let mut events = Vec::new();
        for &byte in bytes {
            match self.reader.push(byte) {
                None => {}
                Some(Decoded::Message(message)) => {
                    // Serialising these plain structs cannot fail; a failure would still
                    // only cost this one event.
                    match serde_json::to_value(message) {
                        Ok(value) => events.push(value),
                        Err(_) => self.drop_one(&mut events),
                    }
                }
                Some(Decoded::Dropped) => self.drop_one(&mut events),
            }
        }
        serde_json::Value::Array(events).to_string()
    }

    fn drop_one(&mut self, events: &mut Vec<serde_json::Value>) {
        self.dropped = self.dropped.saturating_add(1);
        events.push(serde_json::Value::from("Dropped"));
    }

    /// Frames dropped so far.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }
}
