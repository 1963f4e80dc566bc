//! One ground-station page's world: the firmware-in-the-loop world ([`crate::World`]: both
//! ends' applications on virtual Si4432s, the quad in the air) flown by the served pilot
//! ([`super::pilot`]), with a phone attached to the module's HM-10 — the page. Advanced by
//! the caller in steps of virtual time. What the page was sent is decoded here again, so a
//! test can compare the page with it ([`Sent`]), and the setting changes the flight
//! application took are read off its settings table.

use std::collections::VecDeque;
use std::time::Duration;
use telemetry::link::LinkKey;

use flight_app::report::setting_report;
use flight_app::settings::{PARAMS, Settings, handles};
use quad_sim::quad::QuadParams;
use telemetry::link::RateMode;
use telemetry::messages::{Decoded, Message, MessageReader, SettingChange};

use super::pilot::ServedPilot;
use crate::runner::pilot::PilotPlan;
use crate::scenario::Scenario;
use crate::world::World;

/// Bytes waiting for the page; beyond this the oldest are dropped (a stalled page must not
/// grow the server).
pub const TO_PAGE_MAX: usize = 64 * 1024;

/// What a served world is made of (the command line's choices).
#[derive(Debug, Clone)]
pub struct WorldOptions {
    /// The link's rate mode (both ends bound at it).
    pub rate: RateMode,
    /// Seed of the world's noise and radio randomness.
    pub seed: u64,
    /// Extra random packet loss on the air, 0…1.
    pub packet_loss: f64,
    /// The flight side's settings (factory unless changed).
    pub settings: Settings,
    /// The airframe.
    pub quad: QuadParams,
}

impl Default for WorldOptions {
    /// The runner's factory world: factory settings on quad-sim's 250-class quad X, F250,
    /// seed 7, no extra loss.
    fn default() -> Self {
        let factory = crate::runner::Options::factory();
        Self {
            rate: factory.rate,
            seed: factory.seed,
            packet_loss: 0.0,
            settings: factory.settings,
            quad: factory.quad,
        }
    }
}

/// The served world's scenario — the one place a served world is made (both ends' settings,
/// the airframe, the pilot): endless, flown by [`ServedPilot`], the module bound to the
/// flight side at the rate as the runner pairs them.
pub fn scenario(o: &WorldOptions) -> Scenario {
    let trim = PilotPlan::climb(&o.quad, o.settings.get(handles::OUTPUT_IDLE)).trim;
    let mut s = Scenario::flown_by(
        o.settings.clone(),
        o.quad.clone(),
        f64::INFINITY,
        ServedPilot::new(trim),
    );
    s.seed = o.seed;
    s.rate = o.rate;
    s.packet_loss = o.packet_loss;
    // A keyed pair (spec §12: the world hands the flight side its link's key as a bind
    // would) whose module holds the served world's binding phrase: the page proves it to
    // the module (CPace over the HM-10) and gets the change key to sign its setting changes,
    // as a pilot's phone would.
    let mut module = crate::runner::bound_module_settings(o.rate);
    module.link_key = Some(LinkKey::from_bytes(*b"served world key"));
    module.plain = false;
    module.phrase_salt = *b"servesal";
    let _ = module.set_text("phrase", SERVE_PHRASE);
    s.module_settings = Some(module);
    s
}

/// The binding phrase the module of a served world holds (spec §12): the page proves it to
/// get the change key. Printed with the URL; a demo value, public by design.
pub const SERVE_PHRASE: &str = "taulink served demo";

/// What the page was sent (the last message of each kind, as serde renders it) and the
/// setting changes the flight application took, for `/api/sent`.
#[derive(Debug, Default, Clone)]
pub struct Sent {
    /// Kind name → last message JSON.
    pub last: serde_json::Map<String, serde_json::Value>,
    /// Changes of the flight side's settings table since boot (id, wire value), in order.
    pub applied: Vec<SettingChange>,
    /// The flight side's refusals sent to the page (reason and all), in order, at most
    /// [`MAX_REFUSALS`] (the oldest dropped).
    pub refused: Vec<serde_json::Value>,
}

/// Refusals `/api/sent` keeps.
pub const MAX_REFUSALS: usize = 32;

impl Sent {
    fn record(&mut self, message: &Message) {
        // Every variant renders as `{"Kind": body}`.
        if let Ok(serde_json::Value::Object(map)) = serde_json::to_value(message) {
            self.last.extend(map);
        }
        if let Message::ChangeRefused(r) = message
            && let Ok(v) = serde_json::to_value(r)
        {
            if self.refused.len() == MAX_REFUSALS {
                self.refused.remove(0);
            }
            self.refused.push(v);
        }
    }

    /// As JSON: `{"last": {...}, "applied": [{"id":..,"value":..}], "refused": [{..}]}`.
    pub fn to_json(&self) -> String {
        let applied: Vec<_> = self
            .applied
            .iter()
            .map(|c| serde_json::json!({"id": c.id, "value": c.value}))
            .collect();
        serde_json::json!({"last": self.last, "applied": applied, "refused": self.refused})
            .to_string()
    }
}

/// Every parameter's wire value in `settings`.
fn wire_values(settings: &Settings) -> Vec<Option<SettingChange>> {
    (0..PARAMS.len())
        .map(|i| setting_report(settings, u16::try_from(i).unwrap_or(u16::MAX)))
        .collect()
}

/// One page's world.
pub struct Session {
    world: World,
    to_page: VecDeque<u8>,
    reader: MessageReader,
    held: Vec<Option<SettingChange>>,
    /// What the page was sent and the flight side applied.
    pub sent: Sent,
}

impl Session {
    /// A world for `o`, at virtual time 0 (both boards about to power up), a phone attached.
    pub fn new(o: &WorldOptions) -> Self {
        let mut world = World::new(scenario(o));
        world.attach_phone();
        let held = wire_values(&world.flight_settings());
        Self {
            world,
            to_page: VecDeque::new(),
            reader: MessageReader::new(),
            held,
            sent: Sent::default(),
        }
    }

    /// Virtual time since power-up.
    pub fn now(&self) -> Duration {
        self.world.now()
    }

    /// Runs the world up to `t` of virtual time (nothing if it is there already).
    pub fn run_until(&mut self, t: Duration) {
        let now = self.world.now();
        if t > now {
            self.world.run_for(t - now);
        }
        // The records of a run are not kept here: a page's world may run for hours.
        drop(self.world.take_samples());
        drop(self.world.take_module_rx());
        let bytes = self.world.phone_read();
        for &b in &bytes {
            if let Some(Decoded::Message(m)) = self.reader.push(b) {
                self.sent.record(&m);
            }
        }
        self.to_page.extend(bytes);
        let excess = self.to_page.len().saturating_sub(TO_PAGE_MAX);
        self.to_page.drain(..excess);
        let now = wire_values(&self.world.flight_settings());
        for (was, is) in self.held.iter().zip(&now) {
            if was != is
                && let Some(change) = is
            {
                self.sent.applied.push(*change);
            }
        }
        self.held = now;
    }

    /// Bytes from the page, for the module's HM-10.
    pub fn from_page(&mut self, bytes: &[u8]) {
        self.world.phone_write(bytes);
    }

    /// Everything waiting for the page.
    pub fn take_to_page(&mut self) -> Vec<u8> {
        self.to_page.drain(..).collect()
    }
}

#[cfg(test)]
mod tests {
    /// The change key a phone that proved the served phrase gets: the flight link's.
    fn served_change_key(session: &Session) -> telemetry::change_auth::ChangeKey {
        let key = session
            .world
            .flight_settings()
            .link_key()
            .expect("a keyed pair");
        telemetry::change_auth::ChangeKey::from_link_key(&key)
    }

    use super::*;
    use telemetry::change_auth::Signer;
    use telemetry::messages::{RefuseReason, encode_message};

    fn page_messages(session: &mut Session, reader: &mut MessageReader) -> Vec<Message> {
        session
            .take_to_page()
            .iter()
            .filter_map(|&b| reader.push(b))
            .map(|d| match d {
                Decoded::Message(m) => m,
                Decoded::Dropped => panic!("the relay stream lost a frame"),
            })
            .collect()
    }

    /// `SettingChange` of pid.roll.kp to `value`.
    fn kp(value: f32) -> SettingChange {
        let id = PARAMS.iter().position(|p| p.name == "pid.roll.kp").unwrap();
        SettingChange {
            id: id as u16,
            value: flight_app::report::f32_value(value),
        }
    }

    fn send(session: &mut Session, message: Message) {
        let mut frame = [0u8; 48];
        let n = encode_message(&message, &mut frame).unwrap().len();
        session.from_page(&frame[..n]);
    }

    fn s(seconds: f64) -> Duration {
        Duration::from_secs_f64(seconds)
    }

    #[test]
    fn the_page_gets_the_flight_apps_telemetry_and_a_setting_round_trips() {
        let mut session = Session::new(&WorldOptions::default());
        let mut reader = MessageReader::new();
        session.run_until(s(3.0));
        let got = page_messages(&mut session, &mut reader);
        for kind in ["Attitude", "Battery", "LinkStats", "FlightMode", "ArmState"] {
            assert!(
                got.iter().any(|m| format!("{m:?}").starts_with(kind)),
                "no {kind} in {} messages",
                got.len()
            );
        }
        // What the page got is what the server says it sent.
        let last_battery = got.iter().rev().find(|m| matches!(m, Message::Battery(_)));
        assert_eq!(
            last_battery.map(|m| serde_json::to_value(m).unwrap()["Battery"].clone()),
            session.sent.last.get("Battery").cloned()
        );
        // The factory pack of the BrushedSparky world: 1S at 4.15 V, read through the ADC.
        let Some(Message::Battery(b)) = last_battery else {
            panic!("no battery")
        };
        assert!((4_100..=4_200).contains(&b.voltage_mv), "{b:?}");

        // pid.roll.kp to 0.004, written by the page as its frame: FlightApp takes it (on
        // the ground, disarmed) and echoes it.
        // Unsigned first: refused, nothing applied (spec §12.5).
        let change = kp(0.004);
        send(&mut session, Message::SettingChange(change));
        session.run_until(s(3.5));
        assert!(session.sent.applied.is_empty());
        let answer = page_messages(&mut session, &mut reader);
        let Some(Message::ChangeRefused(refused)) = answer
            .iter()
            .find(|m| matches!(m, Message::ChangeRefused(_)))
        else {
            panic!("no refusal in {answer:?}");
        };
        assert_eq!(refused.reason, RefuseReason::NotAuthenticated);
        // Signed with the served world's phrase, after learning the session: applied.
        let mut phone = Signer::new(served_change_key(&session));
        assert!(phone.on_refused(refused));
        send(&mut session, Message::SignedChange(phone.sign(change)));
        session.run_until(s(4.5));
        assert_eq!(session.sent.applied, vec![change]);
        assert!((session.world.flight_settings().get(handles::PID_ROLL_KP) - 0.004).abs() < 1e-7);
        let echoed = page_messages(&mut session, &mut reader);
        assert!(echoed.contains(&Message::SettingChange(change)), "no echo");
    }

    #[test]
    fn a_served_minute_takes_off_hovers_lands_and_disarms_then_flies_again() {
        use super::super::pilot::{CYCLE_S, HOVER_M};
        let mut world = World::new(scenario(&WorldOptions::default()));
        world.run_for(s(crate::WARMUP_S + CYCLE_S + 12.0));
        let samples = world.take_samples();
        let first: Vec<_> = samples.iter().filter(|x| x.t_s < CYCLE_S).collect();
        let top = first.iter().map(|x| x.altitude_m).fold(0.0, f64::max);
        let hover: Vec<_> = first
            .iter()
            .filter(|x| (14.0..30.0).contains(&x.t_s))
            .map(|x| x.altitude_m)
            .collect();
        let (lo, hi) = hover
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), &a| (l.min(a), h.max(a)));
        println!("served minute: top {top:.2} m, hover {lo:.2}–{hi:.2} m");
        // The eye-and-hand height loop is slow; the steps and the turn lift the frame a little.
        assert!((HOVER_M - 2.0..HOVER_M + 3.5).contains(&lo), "{lo}");
        assert!((HOVER_M - 2.0..HOVER_M + 3.5).contains(&hi), "{hi}");
        let airborne_stop = samples.iter().any(|x| {
            x.altitude_m > 0.3
                && x.motors
                    .iter()
                    .all(|m| *m == flight_app::outputs::Command::Stopped)
        });
        assert!(!airborne_stop, "motors stopped in the air");
        let armed = |t: f64| {
            samples
                .iter()
                .find(|x| x.t_s >= t)
                .map(|x| (x.out.armed, x.altitude_m))
                .unwrap()
        };
        assert!(armed(8.0).0, "not armed after the gesture");
        let (after_landing, height) = armed(58.0);
        assert!(
            !after_landing && height < 0.05,
            "{after_landing} at {height} m"
        );
        assert!(armed(CYCLE_S + 8.0).0, "not armed in the second minute");
        assert!(samples.iter().all(|x| x.link_up || x.t_s < 0.0));
    }

    #[test]
    fn the_pilot_flies_the_firmware_and_a_change_in_flight_is_refused() {
        use super::super::pilot::{ARM_AT_S, RATE_FROM_S, RATE_TO_S};
        let warmup = crate::WARMUP_S;
        let mut session = Session::new(&WorldOptions::default());
        let mut reader = MessageReader::new();
        // Armed and hovering, in rate mode (the mode switch mid: rate PID), reported by FlightApp.
        session.run_until(s(warmup + RATE_FROM_S + 2.0));
        let got = page_messages(&mut session, &mut reader);
        let armed_seen = got
            .iter()
            .any(|m| matches!(m, Message::ArmState(a) if a.armed));
        assert!(armed_seen, "never armed after the gesture at {ARM_AT_S} s");
        let modes: Vec<_> = got
            .iter()
            .filter_map(|m| match m {
                Message::FlightMode(f) => Some(*f),
                _ => None,
            })
            .collect();
        assert_eq!(
            modes.last(),
            Some(&telemetry::messages::FlightMode::RatePid),
            "{modes:?}"
        );
        // Up in the air, from the flight side's attitude reports too.
        let roll_seen = got
            .iter()
            .any(|m| matches!(m, Message::Attitude(a) if a.roll_cdeg.unsigned_abs() > 500));
        assert!(roll_seen, "the 15° roll step never showed");

        // A signed change while armed: the first try only teaches the phone the session
        // (the tag and counter are checked first, so a refused change is used up); the
        // second is refused with the reason.
        let mut phone = Signer::new(served_change_key(&session));
        send(&mut session, Message::SignedChange(phone.sign(kp(0.004))));
        session.run_until(s(warmup + RATE_FROM_S + 4.0));
        let first = page_messages(&mut session, &mut reader)
            .into_iter()
            .find_map(|m| match m {
                Message::ChangeRefused(r) => Some(r),
                _ => None,
            })
            .expect("the first try refused");
        assert!(phone.on_refused(&first), "{first:?}");
        send(&mut session, Message::SignedChange(phone.sign(kp(0.004))));
        session.run_until(s(warmup + RATE_TO_S));
        assert!(session.sent.applied.is_empty());
        assert!(
            page_messages(&mut session, &mut reader)
                .iter()
                .any(|m| matches!(m, Message::ChangeRefused(r) if r.reason == RefuseReason::Armed))
        );
    }
}
