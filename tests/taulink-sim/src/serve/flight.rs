//! The flight end of a served world: the link follower's application as the flight
//! firmware's link task has it — `flight_core::report::Reporter` choosing one message per
//! 20 ms, arming / failsafe / mode changes sent out of turn, setting changes from the
//! uplink applied to a `flight_core` settings table while disarmed and echoed — over a
//! scripted flight instead of sensors: attitude steps every 2 s, a slowly draining 4S pack,
//! a flight-mode change every 10 s, armed from 20 s to 80 s of every 100 s, a GPS circle,
//! identification results after each system-identification phase. Values hold still between
//! steps so a test can compare the page with what was sent. Changes from the page pass
//! `flight_core::authority::ChangeGate` as on the flight controller: signed with the served
//! world's phrase, fresh, disarmed — else refused with the reason.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::rc::Rc;

use flight_core::authority::{ChangeGate, Reply};
use flight_core::battery::{BatteryLevel, BatteryStatus};
use flight_core::outputs::Command;
use flight_core::pipeline::LoopOutput;
use flight_core::report::{LinkSeen, Reporter, Snapshot, sysid_message};
use flight_core::settings::Settings;
use flight_core::supervisor::{Decision, FlightMode};
use telemetry::link::LinkKey;
use telemetry::link::core::Follower;
use telemetry::link::follower::FollowerHooks;
use telemetry::messages::{
    Axis, ChangeRefused, Decoded, FRAMED_MAX_BYTES, Gps, GpsFix, Message, MessageReader,
    SettingChange, encode_message,
};

/// Telemetry message period (flight-fw's `REPORT_PERIOD_US`).
const REPORT_PERIOD_US: u64 = 20_000;
/// GPS period.
const GPS_PERIOD_US: u64 = 1_000_000;
/// The script's modes, one per 10 s.
const MODES: [FlightMode; 4] = [
    FlightMode::Attitude,
    FlightMode::RatePid,
    FlightMode::SystemId,
    FlightMode::Attitude,
];

/// What the flight side sent (the last message of each kind, as serde renders it) and the
/// setting changes it applied, for `/api/sent`.
#[derive(Debug, Default, Clone)]
pub struct Sent {
    /// Kind name → last message JSON.
    pub last: BTreeMap<String, serde_json::Value>,
    /// Changes applied to the settings table (id, wire value).
    pub applied: Vec<SettingChange>,
    /// Changes refused (unsigned, wrong phrase, replayed, armed, invalid).
    pub refused: Vec<ChangeRefused>,
}

impl Sent {
    fn record(&mut self, message: &Message) {
        // Every variant renders as `{"Kind": body}`.
        if let Ok(serde_json::Value::Object(map)) = serde_json::to_value(message) {
            self.last.extend(map);
        }
    }

    /// As JSON: `{"last": {...}, "applied": [{"id":..,"value":..}], "refused":
    /// [{"id":..,"reason":".."}]}`.
    pub fn to_json(&self) -> String {
        let applied: Vec<_> = self
            .applied
            .iter()
            .map(|c| serde_json::json!({"id": c.id, "value": c.value}))
            .collect();
        let refused: Vec<_> = self
            .refused
            .iter()
            .map(|r| serde_json::json!({"id": r.id, "reason": format!("{:?}", r.reason)}))
            .collect();
        serde_json::json!({"last": self.last, "applied": applied, "refused": refused}).to_string()
    }
}

/// The scripted flight at virtual time `t_us`.
fn script(t_us: u64) -> (LoopOutput, BatteryStatus) {
    let s = t_us / 1_000_000;
    let step = (s / 2) as f32;
    let cycle = s % 100;
    let armed = (20..80).contains(&cycle);
    let mode = MODES
        .get(((s / 10) % MODES.len() as u64) as usize)
        .copied()
        .unwrap_or(FlightMode::Attitude);
    let attitude_deg = [
        (12.0 * (step * 0.9).sin()).round(),
        (6.0 * (step * 0.5 + 1.0).sin()).round(),
        (step * 15.0) % 360.0 - 180.0,
    ];
    let out = LoopOutput {
        motors: [Command::Stopped; 4],
        decision: Decision::Steady,
        mode,
        mode_changed: false,
        armed,
        failsafe: false,
        attitude_deg,
    };
    // 16.4 V full, 40 mV less every 5 s, 12 A while armed.
    let voltage_mv = 16_400u32.saturating_sub(40 * (s / 5) as u32);
    let battery = BatteryStatus {
        voltage_mv,
        current_ma: if armed { 12_000 } else { 400 },
        consumed_mah: (s * 2) as u32,
        cells: 4,
        level: BatteryLevel::Ok,
        level_changed: false,
    };
    (out, battery)
}

/// A 30 m circle around a field, once a minute.
fn gps(t_us: u64) -> Gps {
    let phase = (t_us as f64 / 60e6) * std::f64::consts::TAU;
    let (north_m, east_m) = (30.0 * phase.cos(), 30.0 * phase.sin());
    let lat = 47.397_742 + north_m / 111_320.0;
    let lon = 8.545_594 + east_m / (111_320.0 * (47.397_742f64.to_radians()).cos());
    Gps {
        latitude_e7: (lat * 1e7) as i32,
        longitude_e7: (lon * 1e7) as i32,
        altitude_cm: 48_830 + 1_500,
        ground_speed_cm_s: (30.0 * std::f64::consts::TAU / 60.0 * 100.0) as u16,
        course_cdeg: ((phase.to_degrees() + 90.0).rem_euclid(360.0) * 100.0) as u16,
        satellites: 14,
        fix: GpsFix::Fix3d,
    }
}

/// The follower's application in a served world.
pub struct FlightSide {
    sent: Rc<RefCell<Sent>>,
    reporter: Reporter,
    reader: MessageReader,
    settings: Settings,
    key: LinkKey,
    gate: ChangeGate,
    reply: Option<Message>,
    last_state: Option<(bool, bool, FlightMode)>,
    last_report_us: u64,
    last_gps_us: u64,
    last_mode: FlightMode,
    sysid_pending: Vec<Message>,
    failsafes: u16,
    was_failsafe: bool,
}

impl FlightSide {
    /// A flight side recording into `sent`, its link keyed with `key` (the phone's changes
    /// are signed under it), `session` its boot's session nonce.
    pub fn new(sent: Rc<RefCell<Sent>>, key: LinkKey, session: u32) -> Self {
        let mut settings = Settings::default();
        settings.set_link_key(Some(key));
        Self {
            sent,
            reporter: Reporter::new(),
            reader: MessageReader::new(),
            settings,
            key,
            gate: ChangeGate::new(session),
            reply: None,
            last_state: None,
            last_report_us: 0,
            last_gps_us: 0,
            last_mode: FlightMode::Attitude,
            sysid_pending: Vec::new(),
            failsafes: 0,
            was_failsafe: false,
        }
    }

    fn send(&mut self, follower: &mut Follower, message: Message) {
        let mut buf = [0u8; FRAMED_MAX_BYTES];
        if let Ok(n) = encode_message(&message, &mut buf) {
            follower
                .downlink_stream
                .write(buf.get(..n).unwrap_or_default());
            self.sent.borrow_mut().record(&message);
        }
    }
}

impl FollowerHooks for FlightSide {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        let failsafe = follower.in_failsafe();
        if failsafe && !self.was_failsafe {
            self.failsafes = self.failsafes.saturating_add(1);
        }
        self.was_failsafe = failsafe;
        let (mut out, battery) = script(now_us);
        out.failsafe = failsafe && out.armed;
        let mut buf = [0u8; 32];
        loop {
            let n = follower.uplink_stream.read(&mut buf);
            if n == 0 {
                break;
            }
            for &b in buf.iter().take(n) {
                if let Some(Decoded::Message(m)) = self.reader.push(b) {
                    // The flight controller's gate: signed, fresh, disarmed.
                    let reply =
                        self.gate
                            .on_message(&m, &mut self.settings, Some(self.key), out.armed);
                    match reply {
                        Some(Reply::Applied(c)) => self.sent.borrow_mut().applied.push(c),
                        Some(Reply::Refused(r)) => self.sent.borrow_mut().refused.push(r),
                        None => {}
                    }
                    if let Some(reply) = reply {
                        self.reply = Some(reply.message());
                    }
                }
            }
        }
        if self.last_mode == FlightMode::SystemId && out.mode != FlightMode::SystemId {
            self.sysid_pending = [(Axis::Roll, 10.2f32), (Axis::Pitch, 10.4), (Axis::Yaw, 7.1)]
                .into_iter()
                .map(|(axis, ln_beta)| {
                    Message::SysIdResult(sysid_message(axis, ln_beta.exp(), 0.0, 0.031, 0.8))
                })
                .collect();
        }
        self.last_mode = out.mode;
        if now_us.saturating_sub(self.last_report_us) < REPORT_PERIOD_US {
            return;
        }
        let stream = &follower.downlink_stream;
        if stream.pending() > 0 || stream.free() < FRAMED_MAX_BYTES {
            return; // one message in flight at most, as on the flight controller
        }
        self.last_report_us = now_us;
        let counters = follower.counters();
        let snap = Snapshot {
            out,
            battery: Some(battery),
            link: LinkSeen {
                rssi_dbm: follower
                    .uplink_rssi_dbm()
                    .map_or(0, |r| i8::try_from(r).unwrap_or(i8::MIN)),
                lq_percent: follower.uplink_lq(),
                downlink: follower.remote_report().map(|r| (r.rssi_dbm, r.lq_percent)),
                rate_mode: follower.params().rate.code(),
                received: counters.received,
                missed: counters.missed,
                failsafes: self.failsafes,
            },
            arming_blockers: 0,
            sysid: None,
        };
        let state = (out.armed, out.failsafe, out.mode);
        let message = if let Some(reply) = self.reply.take() {
            reply
        } else if !self.sysid_pending.is_empty() {
            self.sysid_pending.remove(0)
        } else if self.last_state != Some(state) {
            self.last_state = Some(state);
            Reporter::state(&snap)
        } else if now_us.saturating_sub(self.last_gps_us) >= GPS_PERIOD_US {
            self.last_gps_us = now_us;
            Message::Gps(gps(now_us))
        } else {
            self.reporter.next(&snap)
        };
        self.send(follower, message);
    }
}
