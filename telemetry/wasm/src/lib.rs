//! The ground station's Rust half: the telemetry stream reader (`telemetry::messages`) and
//! the encoders for what the phone sends (setting changes, the module records), exported to JavaScript with
//! wasm-bindgen so the web app decodes with exactly the code the module and the flight side
//! run. Everything crosses the boundary as bytes or JSON text; the logic lives in
//! [`stream`] and [`settings`], which build and test on the host too.

pub mod settings;
pub mod stream;

use wasm_bindgen::prelude::wasm_bindgen;

/// Stream decoder for JavaScript: feed it the bytes as they arrive (any chunking: BLE
/// notifications, serial reads, WebSocket messages), get the decoded events as JSON.
#[wasm_bindgen]
#[derive(Debug, Default)]
pub struct Decoder {
    inner: stream::StreamDecoder,
}

#[wasm_bindgen]
impl Decoder {
    /// A decoder waiting for the first delimiter.
    #[wasm_bindgen(constructor)]
    pub fn new() -> Decoder {
        Decoder::default()
    }

    /// Decodes `bytes`; returns a JSON array of events (see [`stream::StreamDecoder::push`]).
    pub fn push(&mut self, bytes: &[u8]) -> String {
        self.inner.push(bytes)
    }

    /// Frames dropped so far (corrupt, oversize or unknown).
    pub fn dropped(&self) -> u32 {
        self.inner.dropped()
    }
}

/// The framed stream bytes of a setting change (`id` = index in the table,
/// `wire` = [`setting_to_wire`]'s value): what the phone writes to the HM-10, the
/// WebSocket or the serial port. Empty if it cannot be encoded.
#[wasm_bindgen]
pub fn encode_setting_change(id: u16, wire: i32) -> Vec<u8> {
    // Kept default: the JavaScript API's "cannot encode" is an empty array (documented).
    settings::encode_change(id, wire).unwrap_or_default()
}

/// The flight side's parameter table as JSON (see [`settings::table_json`]).
#[wasm_bindgen]
pub fn settings_table() -> String {
    settings::table_json()
}

/// The wire value of `value` for setting `id`, or `undefined` when the setting is unknown
/// or the value outside its range (the flight side would refuse it).
#[wasm_bindgen]
pub fn setting_to_wire(id: u16, value: f64) -> Option<i32> {
    settings::to_wire(id, value)
}

/// The wire value of `value` for setting `id`; throws why the flight side would refuse it
/// ("2 is above the largest value, 1").
#[wasm_bindgen]
pub fn setting_check(id: u16, value: f64) -> Result<i32, wasm_bindgen::JsError> {
    settings::check(id, value).map_err(|e| wasm_bindgen::JsError::new(&e))
}

/// The number a wire value of setting `id` stands for (a choice as its index).
#[wasm_bindgen]
pub fn setting_from_wire(id: u16, wire: i32) -> Option<f64> {
    settings::from_wire(id, wire)
}

/// The phone's half for JavaScript (see [`settings::Phone`]): built from the binding phrase
/// the pilot types into the settings view, held in memory only; proven to the module with
/// CPace, which grants the change key the flight side checks.
#[wasm_bindgen]
#[derive(Debug)]
pub struct Phone {
    inner: settings::Phone,
}

#[wasm_bindgen]
impl Phone {
    /// The phone for `phrase`; throws for an empty phrase or one the phrase rule refuses,
    /// with the reason.
    #[wasm_bindgen(constructor)]
    pub fn new(phrase: &str) -> Result<Phone, wasm_bindgen::JsError> {
        settings::Phone::new(phrase)
            .map(|inner| Phone { inner })
            .map_err(|e| wasm_bindgen::JsError::new(&e))
    }

    /// The framed `Hello` that asks the module for its challenge.
    pub fn hello(&self) -> Result<Vec<u8>, wasm_bindgen::JsError> {
        self.inner
            .hello()
            .map_err(|e| wasm_bindgen::JsError::new(&e))
    }

    /// Where the phone stands: "unknown", "granted", "granted-no-link" or "refused:REASON".
    pub fn standing(&self) -> String {
        match self.inner.standing() {
            settings::Standing::Unknown => "unknown".to_owned(),
            settings::Standing::Granted => "granted".to_owned(),
            settings::Standing::GrantedWithoutLink => "granted-no-link".to_owned(),
            settings::Standing::Refused(why) => format!("refused:{why:?}"),
        }
    }

    /// A module record's event (its JSON) and 32 random bytes: the frame to send next, or
    /// empty.
    pub fn on_module_record(&mut self, record_json: &str, random: &[u8]) -> Vec<u8> {
        self.inner.on_module_record(record_json, random)
    }

    /// The framed record setting the module's phrase to `new_phrase` (or the `Hello` that
    /// comes first); throws for a phrase the rule refuses.
    pub fn set_module_phrase(
        &mut self,
        new_phrase: &str,
    ) -> Result<Vec<u8>, wasm_bindgen::JsError> {
        self.inner
            .set_module_phrase(new_phrase)
            .map_err(|e| wasm_bindgen::JsError::new(&e))
    }

    /// The framed, signed change of setting `id` to `wire` ([`setting_to_wire`]); empty
    /// until the module granted the change key.
    pub fn sign_change(&mut self, id: u16, wire: i32) -> Vec<u8> {
        // Kept default: the JavaScript API's "cannot sign" is an empty array.
        self.inner.sign_change(id, wire).unwrap_or_default()
    }

    /// A `ChangeRefused` event's body as JSON: the frame to send again, or empty.
    pub fn on_refused(&mut self, refused_json: &str) -> Vec<u8> {
        self.inner.on_refused(refused_json)
    }
}
