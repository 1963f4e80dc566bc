//! The flight side's settings as the ground station sees them: the schema of
//! `telemetry::settings` (index = the `SettingChange::id` on the wire; names, kinds, ranges,
//! units, docs), the conversion of a number to its wire value and back (reals as IEEE-754
//! bits, whole numbers and choices as themselves), and the framed `SettingChange` the phone sends.
//! Authority stays on the flight side: it applies only changes signed with the link's change
//! key (spec §12.5) and never while armed, and echoes what it holds, so the app shows a value
//! only once the flight side reported it. [`Phone`] is the phone's half: the binding phrase
//! the pilot typed (checked by the phrase rule, kept in this object, in memory only), proven
//! to the module with CPace (`telemetry::module_record`), which grants the change key; the
//! signer and its counter; and new module phrases sealed in that session.

use serde_json::json;
use telemetry::change_auth::Signer;
use telemetry::framing::{frame, framed_len};
use telemetry::link::check_phrase;
use telemetry::messages::{
    ChangeRefused, EncodeError, FRAMED_MAX_BYTES, Message, SettingChange, encode_message,
};
use telemetry::module_record::{self, ModuleRecord, Outcome, PhoneSession, Refusal};
use telemetry::settings::{Kind, PARAMS, Value, by_id};

/// Where the phone stands with the module.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Standing {
    /// Nothing asked yet, or the module's challenge not answered.
    Unknown,
    /// The module confirmed the phrase; it holds a keyed flight link (changes can be signed).
    Granted,
    /// The module confirmed the phrase but has no keyed flight link yet.
    GrantedWithoutLink,
    /// The module refused (its reason).
    Refused(Refusal),
}

/// The phone's state for one binding phrase.
#[derive(Debug)]
pub struct Phone {
    phrase: String,
    session: Option<PhoneSession>,
    signer: Option<Signer>,
    standing: Standing,
    pending: Option<SettingChange>,
    /// A new module phrase waiting for the session (sent once granted).
    pending_phrase: Option<String>,
    /// The last module phrase sent, to seal again after a stale-counter answer.
    sent_phrase: Option<String>,
}

impl Phone {
    /// The phone for `phrase` (the phrase rule of `telemetry::link::check_phrase`); an error
    /// text for an empty or unusable phrase.
    pub fn new(phrase: &str) -> Result<Self, String> {
        let phrase = checked(phrase)?;
        Ok(Self {
            phrase: phrase.to_owned(),
            session: None,
            signer: None,
            standing: Standing::Unknown,
            pending: None,
            pending_phrase: None,
            sent_phrase: None,
        })
    }

    /// The framed `Hello` that starts an exchange with the module (it answers with its
    /// challenge, [`Phone::on_module_record`]).
    pub fn hello(&self) -> Result<Vec<u8>, String> {
        frame_module(&ModuleRecord::Hello)
    }

    /// Where the phone stands with the module.
    pub fn standing(&self) -> Standing {
        self.standing
    }

    /// A record from the module (its event JSON, e.g. `{"Challenge":{…}}`), with 32 random
    /// bytes for a new exchange (the browser's `crypto.getRandomValues`): the framed record
    /// to send next (empty: none). A challenge is answered with the phrase's proof; a grant
    /// verified gives the change key (and sends a waiting module phrase); an answer about a
    /// module phrase is taken note of (a stale counter seals it again).
    pub fn on_module_record(&mut self, record_json: &str, random: &[u8]) -> Vec<u8> {
        let Ok(record) = serde_json::from_str::<ModuleRecord>(record_json) else {
            return Vec::new();
        };
        match record {
            ModuleRecord::Challenge(challenge) => {
                let random: [u8; 32] =
                    core::array::from_fn(|i| random.get(i).copied().unwrap_or(0));
                let Some((session, response)) =
                    PhoneSession::respond(&self.phrase, &challenge, &random)
                else {
                    return Vec::new();
                };
                self.session = Some(session);
                frame_module(&ModuleRecord::Response(response)).unwrap_or_default()
            }
            ModuleRecord::Granted(granted) => {
                let Some(session) = &self.session else {
                    return Vec::new();
                };
                match session.on_granted(&granted) {
                    Ok(key) => {
                        self.standing = match key {
                            Some(_) => Standing::Granted,
                            None => Standing::GrantedWithoutLink,
                        };
                        self.signer = key.map(Signer::new);
                        match self.pending_phrase.take() {
                            Some(phrase) => self.seal_phrase(&phrase).unwrap_or_default(),
                            None => Vec::new(),
                        }
                    }
                    Err(why) => {
                        self.standing = Standing::Refused(why);
                        Vec::new()
                    }
                }
            }
            ModuleRecord::Answer(answer) => {
                if let Some(session) = &mut self.session {
                    session.on_answer(&answer);
                }
                match answer.outcome {
                    Outcome::Refused(Refusal::Replayed) => match self.sent_phrase.take() {
                        Some(phrase) => self.seal_phrase(&phrase).unwrap_or_default(),
                        None => Vec::new(),
                    },
                    Outcome::Refused(
                        why @ (Refusal::NotAuthenticated
                        | Refusal::NoPhrase
                        | Refusal::NoSession
                        | Refusal::Locked),
                    ) => {
                        self.standing = Standing::Refused(why);
                        Vec::new()
                    }
                    _ => {
                        self.sent_phrase = None;
                        Vec::new()
                    }
                }
            }
            ModuleRecord::Hello
            | ModuleRecord::Response(_)
            | ModuleRecord::SetPhrase(_)
            | ModuleRecord::LinkSecurity(_) => Vec::new(),
        }
    }

    /// The framed record that sets the module's phrase to `new_phrase` (checked by the
    /// phrase rule): sealed in the session once the module granted this phone's phrase;
    /// before that a `Hello`, and the phrase goes once the grant comes (spec §12.5). An
    /// error text for an empty or unusable phrase.
    pub fn set_module_phrase(&mut self, new_phrase: &str) -> Result<Vec<u8>, String> {
        let phrase = checked(new_phrase)?.to_owned();
        if self.session.is_some() && self.standing != Standing::Unknown {
            return self.seal_phrase(&phrase);
        }
        self.pending_phrase = Some(phrase);
        self.hello()
    }

    fn seal_phrase(&mut self, phrase: &str) -> Result<Vec<u8>, String> {
        let session = self.session.as_mut().ok_or("no session with the module")?;
        let record = session
            .set_phrase(phrase)
            .ok_or("no session with the module")?;
        self.sent_phrase = Some(phrase.to_owned());
        frame_module(&ModuleRecord::SetPhrase(record))
    }

    /// The framed, signed change of setting `id` to `wire`; an error until the module
    /// granted the change key.
    pub fn sign_change(&mut self, id: u16, wire: i32) -> Result<Vec<u8>, String> {
        let signer = self
            .signer
            .as_mut()
            .ok_or("the module has not confirmed the phrase (or has no keyed link)")?;
        let change = SettingChange { id, value: wire };
        self.pending = Some(change);
        encode(&Message::SignedChange(signer.sign(change))).map_err(|e| e.to_string())
    }

    /// The flight side refused a change (the `ChangeRefused` event's JSON body): the frame
    /// to send again if the refusal was only for a session or counter this phone did not
    /// know yet (empty: none — the refusal stands and the app shows it).
    pub fn on_refused(&mut self, refused_json: &str) -> Vec<u8> {
        let Ok(refused) = serde_json::from_str::<ChangeRefused>(refused_json) else {
            return Vec::new();
        };
        let retry = self
            .signer
            .as_mut()
            .is_some_and(|signer| signer.on_refused(&refused));
        match self.pending.take() {
            Some(change) if retry && change.id == refused.id => self
                .sign_change(change.id, change.value)
                .unwrap_or_default(),
            _ => Vec::new(),
        }
    }
}

/// `text` as a binding phrase (the rule every end applies), or why not.
fn checked(text: &str) -> Result<&str, String> {
    check_phrase(text)
        .map_err(|e| e.to_string())?
        .ok_or_else(|| "no binding phrase".to_owned())
}

fn frame_module(record: &ModuleRecord) -> Result<Vec<u8>, String> {
    let mut payload = [0u8; module_record::MAX_PAYLOAD_BYTES];
    let n = module_record::encode(record, &mut payload).ok_or("module record too long")?;
    let mut out = [0u8; framed_len(module_record::MAX_PAYLOAD_BYTES)];
    let framed =
        frame(payload.get(..n).unwrap_or_default(), &mut out).map_err(|e| e.to_string())?;
    Ok(framed.to_vec())
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

/// `[{"id":0,"name":"output.protocol","unit":"","doc":"…","kind":"choice","choices":[...],
/// "default":0}, ...]`; reals and whole numbers carry `"min"` and `"max"`.
pub fn table_json() -> String {
    let rows: Vec<serde_json::Value> = PARAMS
        .iter()
        .enumerate()
        .map(|(id, p)| {
            let mut row = json!({
                "id": id,
                "name": p.name,
                "unit": p.unit(),
                "doc": p.doc(),
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

/// The wire value of `value` for setting `id`; `None` for an unknown setting or a value the
/// flight side would refuse (outside the range, not a whole number, not a choice).
pub fn to_wire(id: u16, value: f64) -> Option<i32> {
    check(id, value).ok()
}

/// The wire value of `value` for setting `id`, or why the flight side would refuse it, in
/// words for the pilot ("2 is above the largest value, 1").
pub fn check(id: u16, value: f64) -> Result<i32, String> {
    let p = by_id(id).ok_or("no such setting")?;
    if !value.is_finite() {
        return Err("not a number".into());
    }
    let unit = match p.unit() {
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
    // The schema's own check (the flight side's) has the last word.
    p.from_bits(bits)
        .map_err(|e| e.to_string())
        .map(|_| bits as i32)
}

/// The number wire value `wire` of setting `id` stands for.
pub fn from_wire(id: u16, wire: i32) -> Option<f64> {
    by_id(id)?.from_bits(wire as u32).ok().map(number)
}

#[cfg(test)]
mod tests {
    use super::*;
    use telemetry::settings::find;

    #[test]
    fn wire_values_are_the_schemas_bits_and_refusals_say_why() {
        let (id, _) = find("pid.roll.kp").unwrap();
        let id = id as u16;
        let wire = to_wire(id, 0.004).unwrap();
        assert_eq!(wire, 0.004f32.to_bits() as i32);
        assert_eq!(from_wire(id, wire), Some(f64::from(0.004f32)));
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
        let doc_of = |name: &str| rows.iter().find(|r| r["name"] == name).unwrap()["doc"].clone();
        assert_eq!(
            doc_of("rate.max_dps"),
            "Rate modes: the rate full stick commands."
        );
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
