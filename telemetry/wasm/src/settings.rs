//! The flight side's settings as the ground station sees them: the parameter table of
//! `flight_core::settings` (index = the `SettingChange::id` on the wire), the conversion of a
//! number to its wire value and back (`flight_core::report`: reals as IEEE-754 bits, whole
//! numbers and choices as themselves), and the framed `SettingChange` the phone sends.
//! Authority stays on the flight side: it applies only changes signed with the binding
//! phrase's key (spec §12.5) and never while armed, and echoes what it holds, so the app
//! shows a value only once the flight side reported it. [`Phone`] is the signing half: the
//! key derived from the phrase the pilot typed (kept in this object, in memory only), the
//! counter, and the session learnt from the flight side's refusals.

use flight_core::settings::{Kind, PARAMS, Param, Value};
use serde_json::json;
use telemetry::change_auth::Signer;
use telemetry::framing::{frame, framed_len};
use telemetry::link::{LinkKey, key_for_phrase};
use telemetry::messages::{
    ChangeRefused, EncodeError, FRAMED_MAX_BYTES, Message, SettingChange, encode_message,
};
use telemetry::module_record::{self, KeyAnswer, KeySigner, ModuleRecord};

/// The phone's signing state for one binding phrase.
#[derive(Debug, Clone)]
pub struct Phone {
    signer: Signer,
    fingerprint: String,
    pending: Option<SettingChange>,
    /// Seals new module keys under this phrase's key (the module's current one).
    key_signer: KeySigner,
    /// The module key last sent signed, to send again after a stale-session answer.
    pending_module: Option<LinkKey>,
}

impl Phone {
    /// The phone for `phrase` (the rules of `telemetry::link::key_for_phrase`); an error
    /// text for an empty or unusable phrase.
    pub fn new(phrase: &str) -> Result<Self, String> {
        let key = key_for_phrase(phrase)
            .map_err(|e| e.to_string())?
            .ok_or_else(|| "no binding phrase: the flight side refuses every change".to_owned())?;
        Ok(Self {
            signer: Signer::new(&key),
            fingerprint: key.fingerprint().to_string(),
            pending: None,
            key_signer: KeySigner::new(&key),
            pending_module: None,
        })
    }

    /// The framed record that sets the module's phrase to `new_phrase`, sealed and signed
    /// under this phone's phrase, which must be the module's current one (spec §12.5): the
    /// module applies it at once. An error text for an empty or unusable phrase.
    pub fn sign_module_phrase(&mut self, new_phrase: &str) -> Result<Vec<u8>, String> {
        let key = phrase_key(new_phrase)?;
        self.pending_module = Some(key);
        frame_module(&ModuleRecord::SignedKey(self.key_signer.seal(&key)))
    }

    /// The module answered (the `KeyAnswer` event's JSON body): the frame to send again if
    /// the refusal was only for a session or counter this phone did not know (empty: none —
    /// the answer stands and the app shows it).
    pub fn on_module_answer(&mut self, answer_json: &str) -> Vec<u8> {
        let Ok(answer) = serde_json::from_str::<KeyAnswer>(answer_json) else {
            return Vec::new();
        };
        let retry = self.key_signer.on_answer(&answer);
        match self.pending_module.take() {
            Some(key) if retry => {
                self.pending_module = Some(key);
                frame_module(&ModuleRecord::SignedKey(self.key_signer.seal(&key)))
                    .unwrap_or_default()
            }
            _ => Vec::new(),
        }
    }

    /// The key's fingerprint, as the flight console and the module show it.
    pub fn fingerprint(&self) -> &str {
        &self.fingerprint
    }

    /// The framed, signed change of setting `id` to `wire`.
    pub fn sign_change(&mut self, id: u16, wire: i32) -> Result<Vec<u8>, EncodeError> {
        let change = SettingChange { id, value: wire };
        self.pending = Some(change);
        encode(&Message::SignedChange(self.signer.sign(change)))
    }

    /// The flight side refused a change (the `ChangeRefused` event's JSON body): the frame
    /// to send again if the refusal was only for a session or counter this phone did not
    /// know yet (empty: none — the refusal stands and the app shows it).
    pub fn on_refused(&mut self, refused_json: &str) -> Vec<u8> {
        let Ok(refused) = serde_json::from_str::<ChangeRefused>(refused_json) else {
            return Vec::new();
        };
        let retry = self.signer.on_refused(&refused);
        match self.pending.take() {
            Some(change) if retry && change.id == refused.id => self
                .sign_change(change.id, change.value)
                .unwrap_or_default(),
            _ => Vec::new(),
        }
    }
}

fn phrase_key(phrase: &str) -> Result<LinkKey, String> {
    key_for_phrase(phrase)
        .map_err(|e| e.to_string())?
        .ok_or_else(|| "an empty phrase: the module keeps its phrase".to_owned())
}

fn frame_module(record: &ModuleRecord) -> Result<Vec<u8>, String> {
    let mut payload = [0u8; module_record::MAX_PAYLOAD_BYTES];
    let n = module_record::encode(record, &mut payload).ok_or("module record too long")?;
    let mut out = [0u8; framed_len(module_record::MAX_PAYLOAD_BYTES)];
    let framed =
        frame(payload.get(..n).unwrap_or_default(), &mut out).map_err(|e| e.to_string())?;
    Ok(framed.to_vec())
}

/// The framed record that proposes `phrase` as the module's phrase, for a phone that does
/// not know the module's current one: the module applies it only after the pilot confirms
/// on the radio ("Phone Phrase", showing the fingerprint). An error text for an empty or
/// unusable phrase.
pub fn propose_module_phrase(phrase: &str) -> Result<Vec<u8>, String> {
    frame_module(&ModuleRecord::ProposeKey(phrase_key(phrase)?.to_bytes()))
}

/// The fingerprint of `phrase`'s key, to compare with the radio's confirmation.
pub fn phrase_fingerprint(phrase: &str) -> Result<String, String> {
    Ok(phrase_key(phrase)?.fingerprint().to_string())
}

fn encode(message: &Message) -> Result<Vec<u8>, EncodeError> {
    let mut out = [0u8; FRAMED_MAX_BYTES];
    Ok(encode_message(message, &mut out)?.to_vec())
}

/// The framed stream bytes of `SettingChange { id, value: wire }`.
pub fn encode_change(id: u16, wire: i32) -> Result<Vec<u8>, EncodeError> {
    let mut out = [0u8; FRAMED_MAX_BYTES];
    Ok(encode_message(
        &Message::SettingChange(SettingChange { id, value: wire }),
        &mut out,
    )?
    .to_vec())
}

fn number(value: Value) -> f64 {
    match value {
        Value::F32(v) => f64::from(v),
        Value::U32(v) => f64::from(v),
    }
}

/// The unit a setting's value is in, read from its name: the table names a physical
/// quantity with its unit last (`rate.max_dps`, `output.min_us`); "" for a pure number.
pub fn unit(name: &str) -> &'static str {
    const SUFFIXES: [(&str, &str); 9] = [
        ("_mv_per_a", "mV/A"),
        ("_hz", "Hz"),
        ("_us", "µs"),
        ("_ms", "ms"),
        ("_mv", "mV"),
        ("_dps", "°/s"),
        ("_deg", "°"),
        ("_mps", "m/s"),
        ("_s", "s"),
    ];
    SUFFIXES
        .iter()
        .find(|(suffix, _)| name.ends_with(suffix))
        .map_or("", |(_, unit)| unit)
}

/// `[{"id":0,"name":"output.protocol","unit":"","kind":"choice","choices":[...],"default":0},
/// ...]`; reals and whole numbers carry `"min"` and `"max"`.
pub fn table_json() -> String {
    let rows: Vec<serde_json::Value> = PARAMS
        .iter()
        .enumerate()
        .map(|(id, p)| {
            let mut row = json!({
                "id": id,
                "name": p.name,
                "unit": unit(p.name),
                "default": number(p.default),
            });
            let extra = match p.kind {
                Kind::F32 { min, max } => {
                    json!({"kind": "real", "min": f64::from(min), "max": f64::from(max)})
                }
                Kind::U32 { min, max } => json!({"kind": "whole", "min": min, "max": max}),
                Kind::Choice(names) => json!({"kind": "choice", "choices": names}),
            };
            if let (Some(row), serde_json::Value::Object(extra)) = (row.as_object_mut(), extra) {
                row.extend(extra);
            }
            row
        })
        .collect();
    serde_json::Value::Array(rows).to_string()
}

fn param(id: u16) -> Option<&'static Param> {
    PARAMS.get(usize::from(id))
}

/// The wire value of `value` for setting `id`; `None` for an unknown setting or a value the
/// flight side would refuse (outside the range, not a whole number, not a choice).
pub fn to_wire(id: u16, value: f64) -> Option<i32> {
    check(id, value).ok()
}

/// The wire value of `value` for setting `id`, or why the flight side would refuse it, in
/// words for the pilot ("2 is above the largest value, 1").
pub fn check(id: u16, value: f64) -> Result<i32, String> {
    let p = param(id).ok_or("no such setting")?;
    if !value.is_finite() {
        return Err("not a number".into());
    }
    let unit = match unit(p.name) {
        "" => String::new(),
        u => format!(" {u}"),
    };
    let bits = match p.kind {
        Kind::F32 { min, max } => {
            let v = value as f32;
            if v < min {
                return Err(format!("{v} is below the smallest value, {min}{unit}"));
            }
            if v > max {
                return Err(format!("{v} is above the largest value, {max}{unit}"));
            }
            v.to_bits()
        }
        Kind::U32 { min, max } => {
            if value.fract() != 0.0 {
                return Err(format!("{value} is not a whole number"));
            }
            if value < f64::from(min) {
                return Err(format!("{value} is below the smallest value, {min}{unit}"));
            }
            if value > f64::from(max) {
                return Err(format!("{value} is above the largest value, {max}{unit}"));
            }
            value as u32
        }
        Kind::Choice(names) => {
            if value.fract() != 0.0 || value < 0.0 || value >= names.len() as f64 {
                return Err(format!("not one of {}", names.join(", ")));
            }
            value as u32
        }
    };
    // The flight side's own check has the last word.
    p.from_bits(bits)
        .map_err(|e| e.to_string())
        .map(|_| bits as i32)
}

/// The number wire value `wire` of setting `id` stands for.
pub fn from_wire(id: u16, wire: i32) -> Option<f64> {
    param(id)?.from_bits(wire as u32).ok().map(number)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flight_core::authority::{ChangeGate, Reply};
    use telemetry::messages::{Decoded, MessageReader};

    fn decode(bytes: &[u8]) -> Message {
        let mut reader = MessageReader::new();
        let got: Vec<_> = bytes.iter().filter_map(|&b| reader.push(b)).collect();
        match got.as_slice() {
            [Decoded::Message(m)] => *m,
            other => panic!("one message expected: {other:?}"),
        }
    }

    /// The page against the flight side's own gate: the right phrase gets its change applied
    /// after one refusal that tells it the session; a wrong phrase is refused and not
    /// retried.
    #[test]
    fn the_page_signs_changes_the_flight_side_accepts_only_with_the_right_phrase() {
        let phrase = "correct horse battery staple";
        let (id, _) = find("pid.roll.kp").unwrap();
        let wire = to_wire(id as u16, 0.004).unwrap();
        for (typed, applied) in [(phrase, true), ("a wrong phrase", false)] {
            let mut flight = flight_core::settings::Settings::default();
            flight.set_link_key(Some(telemetry::link::LinkKey::from_phrase(phrase)));
            let key = flight.link_key();
            let mut gate = ChangeGate::new(0x1234_5678);
            let mut phone = Phone::new(typed).unwrap();
            let mut frame = phone.sign_change(id as u16, wire).unwrap();
            let mut answers = Vec::new();
            while !frame.is_empty() && answers.len() < 5 {
                let reply = gate
                    .on_message(&decode(&frame), &mut flight, key, false)
                    .unwrap();
                answers.push(reply);
                frame = match reply {
                    Reply::Refused(r) => phone.on_refused(&serde_json::to_string(&r).unwrap()),
                    Reply::Applied(_) => Vec::new(),
                };
            }
            let last = answers.last().copied().unwrap();
            assert_eq!(
                matches!(last, Reply::Applied(_)),
                applied,
                "{typed}: {answers:?}"
            );
            assert_eq!(answers.len(), 2, "one refusal, one more try: {answers:?}");
            assert_eq!(
                flight.get(flight_core::settings::handles::PID_ROLL_KP) == 0.004,
                applied
            );
        }
        assert!(Phone::new("").is_err());
        assert_eq!(
            Phone::new(phrase).unwrap().fingerprint(),
            telemetry::link::LinkKey::from_phrase(phrase)
                .fingerprint()
                .to_string()
        );
    }
    use flight_core::report::f32_value;
    use flight_core::settings::Settings;

    fn find(name: &str) -> Option<(usize, &'static Param)> {
        PARAMS.iter().enumerate().find(|(_, p)| p.name == name)
    }

    #[test]
    fn wire_values_are_what_the_flight_side_applies() {
        let (id, _) = find("pid.roll.kp").unwrap();
        let id = id as u16;
        let wire = to_wire(id, 0.004).unwrap();
        assert_eq!(wire, f32_value(0.004));
        let mut settings = Settings::default();
        let (result, echo) =
            flight_core::report::apply_setting(&mut settings, SettingChange { id, value: wire });
        assert_eq!(result, Ok(()));
        assert_eq!(
            from_wire(id, echo.unwrap().value),
            Some(f64::from(0.004f32))
        );
        // Outside the range: refused here as the flight side would, and said why.
        assert_eq!(to_wire(id, 2.0), None);
        assert_eq!(
            check(id, 2.0),
            Err("2 is above the largest value, 1".into())
        );
        let (rate, _) = find("rate.max_dps").unwrap();
        assert_eq!(
            check(rate as u16, 10.0),
            Err("10 is below the smallest value, 30 °/s".into())
        );
        let (cells, _) = find("battery.cells").unwrap();
        assert_eq!(
            check(cells as u16, 2.5),
            Err("2.5 is not a whole number".into())
        );
        assert_eq!(check(cells as u16, f64::NAN), Err("not a number".into()));
        let (choice, _) = find("mixer.frame").unwrap();
        assert_eq!(to_wire(choice as u16, 1.0), Some(1));
        assert_eq!(to_wire(choice as u16, 1.5), None);
        assert_eq!(to_wire(choice as u16, 9.0), None);
        assert_eq!(
            check(choice as u16, 9.0),
            Err("not one of quad-x, quad-plus, hex-x".into())
        );
        assert_eq!(to_wire(u16::MAX, 1.0), None);
        assert_eq!(check(u16::MAX, 1.0), Err("no such setting".into()));
    }

    #[test]
    fn table_lists_every_parameter_in_wire_order() {
        let table: serde_json::Value = serde_json::from_str(&table_json()).unwrap();
        let rows = table.as_array().unwrap();
        assert_eq!(rows.len(), PARAMS.len());
        for (id, (row, p)) in rows.iter().zip(PARAMS).enumerate() {
            assert_eq!(row["id"], id);
            assert_eq!(row["name"], p.name);
        }
        let unit_of = |name: &str| rows.iter().find(|r| r["name"] == name).unwrap()["unit"].clone();
        assert_eq!(unit_of("rate.max_dps"), "°/s");
        assert_eq!(unit_of("battery.current_mv_per_a"), "mV/A");
        assert_eq!(unit_of("arm.idle_disarm_ms"), "ms");
        assert_eq!(unit_of("lqg.tau_s"), "s");
        assert_eq!(unit_of("failsafe.descent_mps"), "m/s");
        assert_eq!(unit_of("pid.roll.kp"), "");
    }

    #[test]
    fn a_change_is_one_stream_frame() {
        let bytes = encode_change(3, -7).unwrap();
        let mut reader = telemetry::messages::MessageReader::new();
        let got: Vec<_> = bytes.iter().filter_map(|&b| reader.push(b)).collect();
        assert_eq!(
            got,
            vec![telemetry::messages::Decoded::Message(
                Message::SettingChange(SettingChange { id: 3, value: -7 })
            )]
        );
    }
}
