//! The telemetry stream to JSON: `telemetry::messages::MessageReader` over any chunking of
//! the byte stream, each decoded message serialised with serde as the Rust type describes
//! it (`{"Battery":{"voltage_mv":11870,...}}`, `{"FlightMode":"AltitudeHold"}`), each
//! dropped frame as the string `"Dropped"`. The HM-10 relay's frames are the link frames
//! byte for byte (module-core `records`), so the same reader serves the phone, the flight
//! USB console and the simulator. Records the module itself sends the phone
//! (`telemetry::module_record`: its challenge, grant, answers and link security) become
//! their own events, e.g. `{"Answer":{"outcome":"Applied","counter":1}}`.

use telemetry::framing::{Deframed, Deframer, framed_len};
use telemetry::messages::{FRAMED_MAX_BYTES, Message};
use telemetry::module_record;

/// The longest frame: a message's or a module record's.
const MAX_FRAME: usize = {
    let module = framed_len(module_record::MAX_PAYLOAD_BYTES);
    if module > FRAMED_MAX_BYTES {
        module
    } else {
        FRAMED_MAX_BYTES
    }
};

/// Decodes a byte stream into JSON events; bounded by the reader (one frame).
#[derive(Debug, Default)]
pub struct StreamDecoder {
    reader: Deframer<MAX_FRAME>,
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
                Some(Deframed::Frame { .. }) => {
                    let payload = self.reader.payload();
                    // Serialising these plain structs cannot fail; a failure would still
                    // only cost this one event.
                    let value = if module_record::is_module_payload(payload) {
                        module_record::decode(payload)
                            .ok()
                            .and_then(|r| serde_json::to_value(r).ok())
                    } else {
                        postcard::from_bytes::<Message>(payload)
                            .ok()
                            .and_then(|m| serde_json::to_value(m).ok())
                    };
                    match value {
                        Some(value) => events.push(value),
                        None => self.drop_one(&mut events),
                    }
                }
                Some(Deframed::Overflow | Deframed::Corrupt) => self.drop_one(&mut events),
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
