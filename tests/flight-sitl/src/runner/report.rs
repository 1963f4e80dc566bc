//! The figures of one run, measured on the world's record alone ([`extract`] is a pure
//! function of [`Sitl`] and the [`Plan`] the run followed), and their JSON form.

use std::fmt::Write as _;

use flight_app::battery::BatteryLevel;
use flight_app::outputs::Command;
use flight_app::supervisor::Decision;
use telemetry::link::RateMode;

use super::{Kind, Plan};
use crate::scenario::End;
use crate::world::{Sample, Sitl, WatchdogResets};

/// Above this height the frame counts as airborne for `motors_stopped_airborne`, m.
pub const AIRBORNE_M: f64 = 0.3;
/// At or below this height the frame is on the ground, m (the simulated ground holds it at
/// exactly 0).
pub const GROUND_M: f64 = 0.01;

/// What one run did.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// The scenario.
    pub kind: Kind,
    /// The link's rate mode.
    pub rate: RateMode,
    /// The seed.
    pub seed: u64,
    /// Independent-watchdog resets per end.
    pub watchdog_resets: WatchdogResets,
    /// Boots of the flight controller (power-on and watchdog).
    pub flight_boots: usize,
    /// Highest true altitude above the ground, m.
    pub max_altitude_m: f64,
    /// The first entry into link failsafe (after the fault, if any), s.
    pub failsafe_at_s: Option<f64>,
    /// The last disarm (armed → disarmed), s.
    pub disarmed_at_s: Option<f64>,
    /// Why that disarm (the supervisor's decision, or "reboot"/"power-off").
    pub disarm_reason: Option<&'static str>,
    /// The true height above the ground at that disarm, m.
    pub disarm_height_m: Option<f64>,
    /// Sink rate at the last touchdown after having been airborne, m/s (positive down).
    pub touchdown_speed_mps: Option<f64>,
    /// The motors were ever all stopped while the frame was above `AIRBORNE_M`.
    pub motors_stopped_airborne: bool,
    /// How the run ended (see [`final_state`]).
    pub final_state: &'static str,
    /// The fault began, s.
    pub fault_at_s: Option<f64>,
    /// The fault ended, s.
    pub fault_end_s: Option<f64>,
    /// From the fault to the failsafe, s.
    pub failsafe_delay_s: Option<f64>,
    /// Control back to the pilot after the fault (`ControlRecovered`), s.
    pub recovered_at_s: Option<f64>,
    /// Motors ran after a disarm without a new arming.
    pub rearmed_motors: bool,
    /// The first arming, s.
    pub armed_at_s: Option<f64>,
    /// Armings in the run.
    pub armings: usize,
    /// The flight settings failed to load at the first boot (None: the world did not say).
    pub settings_error_at_boot: Option<bool>,
    /// The battery reached warning, s.
    pub battery_warning_at_s: Option<f64>,
    /// The battery reached critical, s.
    pub battery_critical_at_s: Option<f64>,
    /// A GPS receiver flew.
    pub gps: bool,
    /// The wind from the north, m/s.
    pub wind_mps: f64,
    /// The hold scenarios' figures, and for a link cut with a fix the failsafe's hold
    /// (`held_position_drift_m`, `altitude_error_max_m`).
    pub hold: super::hold::Figures,
    /// `attitude-step`: the stick's way and the attitude loop's response.
    pub step: Option<StepFigures>,
    /// A reset in the air (`panic`, `hang`): the figures of the resumed flight.
    pub resume: Option<ResumeFigures>,
}

/// The `attitude-step` figures, all from the stick's move (the step's `fault_at_s`) unless
/// named otherwise.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepFigures {
    /// The commanded roll, deg (the stick × `attitude.max_deg`).
    pub target_deg: f64,
    /// The transport: until the first loop that flies the new stick (the setpoint's
    /// arrival at the flight controller: PPM frame, module, uplink, follower), s.
    pub setpoint_arrival_s: Option<f64>,
    /// Until the true roll rate first exceeds 5 °/s, s.
    pub rolling_s: Option<f64>,
    /// Until the true roll is first within 1° of the target, s (what a pilot feels).
    pub within_1deg_s: Option<f64>,
    /// The same from the setpoint's arrival, s (the attitude loop alone; comparable with
    /// figures measured with the channels handed to the link directly).
    pub within_1deg_from_setpoint_s: Option<f64>,
    /// Peak roll beyond the target while the stick is held, % of the target.
    pub overshoot_pct: Option<f64>,
}

/// A resumed flight's figures (the `panic` and `hang` scenarios).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ResumeFigures {
    /// The flight board came back as a resumed flight (not a cold boot).
    pub resumed: bool,
    /// From the fault to the motors stopping (the panic handler at once; a hang keeps the
    /// last commands until the IWDG), s.
    pub motors_off_after_s: Option<f64>,
    /// How long the motors stayed stopped: the reset and the resumed boot, s.
    pub motors_off_for_s: Option<f64>,
    /// From the motors back to the link's word (armed again in the recorded mode), s.
    pub link_word_after_s: Option<f64>,
    /// How far the frame sank from its height at the fault until the link's word gave it
    /// back to the pilot, m (after that the pilot flies it).
    pub drop_m: Option<f64>,
}

/// The resume's figures from the samples after the fault at `at_s`.
fn resume_figures(sitl: &Sitl, at_s: f64) -> ResumeFigures {
    let s: Vec<&Sample> = sitl.samples.iter().filter(|x| x.t_s >= at_s).collect();
    let height = s.first().map(|x| x.altitude_m);
    let off = s.iter().find(|x| stopped(x)).map(|x| x.t_s);
    let back = off.and_then(|o| s.iter().find(|x| x.t_s > o && !stopped(x)).map(|x| x.t_s));
    let word = back.and_then(|b| {
        s.iter()
            .find(|x| x.t_s >= b && x.out.decision == Decision::Resumed)
            .map(|x| x.t_s)
    });
    let lowest = word.map(|w| {
        s.iter()
            .filter(|x| x.t_s <= w)
            .map(|x| x.altitude_m)
            .fold(f64::INFINITY, f64::min)
    });
    ResumeFigures {
        resumed: sitl
            .boots
            .iter()
            .any(|b| b.end == End::Flight && b.cause == crate::BootCause::Resumed),
        motors_off_after_s: off.map(|o| o - at_s),
        motors_off_for_s: off.zip(back).map(|(o, b)| b - o),
        link_word_after_s: word.zip(back).map(|(w, b)| w - b),
        drop_m: height.zip(lowest).map(|(h, l)| (h - l).max(0.0)),
    }
}

/// The step's figures from the samples between the stick's move `at_s` and its release
/// `end_s`, for a roll target of `target_deg`.
fn step_figures(s: &[Sample], at_s: f64, end_s: f64, target_deg: f64) -> StepFigures {
    let held: Vec<&Sample> = s
        .iter()
        .filter(|x| x.t_s >= at_s && x.t_s < end_s)
        .collect();
    let first = |f: &dyn Fn(&Sample) -> bool| held.iter().find(|x| f(x)).map(|x| x.t_s - at_s);
    let stick = f64::from(super::STEP_ROLL_STICK);
    let setpoint_arrival_s = first(&|x| f64::from(x.link_sticks.roll) > stick * 0.9);
    let within_1deg_s = first(&|x| (x.truth.euler_deg[0] - target_deg).abs() < 1.0);
    let peak = held
        .iter()
        .map(|x| x.truth.euler_deg[0])
        .fold(f64::NEG_INFINITY, f64::max);
    StepFigures {
        target_deg,
        setpoint_arrival_s,
        rolling_s: first(&|x| x.truth.rate_dps[0] > 5.0),
        within_1deg_s,
        within_1deg_from_setpoint_s: within_1deg_s.zip(setpoint_arrival_s).map(|(w, a)| w - a),
        overshoot_pct: peak
            .is_finite()
            .then(|| ((peak - target_deg) / target_deg * 100.0).max(0.0)),
    }
}

fn stopped(s: &Sample) -> bool {
    s.motors.iter().all(|m| *m == Command::Stopped)
}

fn decision_name(d: Decision) -> &'static str {
    match d {
        Decision::DisarmedByPilot => "pilot",
        Decision::DisarmedIdle => "idle",
        Decision::DisarmedFailsafe => "failsafe-landed",
        Decision::DisarmedLastResort => "failsafe-last-resort",
        Decision::DisarmedSensorFault => "sensor-fault",
        _ => "other",
    }
}

/// How a run ended, from its last sample: `powered-off`, `failsafe-descending`,
/// `armed-flying`, `armed-on-ground`, `disarmed-airborne` (falling), `disarmed-on-ground`,
/// or `no-record` (the flight loop never produced an output).
pub fn final_state(last: Option<&Sample>) -> &'static str {
    let Some(s) = last else {
        return "no-record";
    };
    let airborne = s.altitude_m > GROUND_M;
    match (s.flight_up, s.out.armed, s.out.failsafe, airborne) {
        (false, ..) => "powered-off",
        (true, true, true, true) => "failsafe-descending",
        (true, true, false, true) => "armed-flying",
        (true, true, _, false) => "armed-on-ground",
        (true, false, _, true) => "disarmed-airborne",
        (true, false, _, false) => "disarmed-on-ground",
    }
}

/// The figures of `sitl`, a run of `plan`.
pub fn extract(sitl: &Sitl, plan: &Plan) -> Report {
    let s = &sitl.samples;
    let after_fault = |t: f64| plan.fault_at_s.is_none_or(|a| t >= a);
    let max_altitude_m = s.iter().map(|x| x.altitude_m).fold(0.0, f64::max);
    let failsafe_at_s = s
        .windows(2)
        .filter_map(|w| match w {
            [a, b] if !a.out.failsafe && b.out.failsafe && after_fault(b.t_s) => Some(b.t_s),
            _ => None,
        })
        .next();
    // Arming and disarming edges (a reboot loses the armed state: an edge too).
    let mut armed = false;
    let mut may_run = false;
    let mut armed_at_s = None;
    let mut armings = 0;
    let mut disarm: Option<&Sample> = None;
    let mut rearmed_motors = false;
    for x in s {
        let now = x.flight_up && x.out.armed;
        if x.out.decision == Decision::Armed && x.flight_up {
            may_run = true;
        }
        if now && !armed {
            armings += 1;
            armed_at_s.get_or_insert(x.t_s);
        }
        if armed && !now {
            disarm = Some(x);
            may_run = false;
        }
        if !now && !may_run && !stopped(x) && armings > 0 {
            rearmed_motors = true;
        }
        armed = now;
    }
    let disarm_reason = disarm.map(|x| {
        if !x.flight_up {
            "power-off"
        } else if x.out.decision == Decision::Steady {
            "reboot"
        } else {
            decision_name(x.out.decision)
        }
    });
    let mut been_up = false;
    let mut touchdown_speed_mps = None;
    for w in s.windows(2) {
        if let [a, b] = w {
            been_up |= a.altitude_m > AIRBORNE_M;
            if been_up && a.altitude_m > GROUND_M && b.altitude_m <= GROUND_M {
                touchdown_speed_mps = Some(-a.climb_mps);
            }
        }
    }
    let motors_stopped_airborne = s.iter().any(|x| x.altitude_m > AIRBORNE_M && stopped(x));
    let recovered_at_s = s
        .iter()
        .find(|x| x.out.decision == Decision::ControlRecovered && after_fault(x.t_s))
        .map(|x| x.t_s);
    let level = |l: BatteryLevel| s.iter().find(|x| x.battery == l).map(|x| x.t_s);
    let hold = match (plan.kind, plan.hold_from_s) {
        (k, Some(from)) if k.is_hold() => {
            let timeline = super::hold::Timeline::of(k, from);
            super::hold::measure(sitl, k, &timeline, plan.duration_s)
        }
        (Kind::LinkCut, _) if plan.gps => {
            let hold_s = f64::from(flight_app::pipeline::FAILSAFE_HOLD_MS) / 1_000.0;
            let held = failsafe_at_s.and_then(|f| super::hold::failsafe_hold(sitl, f, hold_s));
            super::hold::Figures {
                held_position_drift_m: held.map(|h| h.0),
                altitude_error_max_m: held.map(|h| h.1),
                ..super::hold::Figures::default()
            }
        }
        _ => super::hold::Figures::default(),
    };
    let step = match (plan.kind, plan.fault_at_s, plan.fault_end_s) {
        (Kind::AttitudeStep, Some(at), Some(end)) => {
            let max_deg = f64::from(
                sitl.settings
                    .get(flight_app::settings::handles::ATTITUDE_MAX_DEG),
            );
            let target = f64::from(super::STEP_ROLL_STICK) * max_deg;
            Some(step_figures(s, at, end, target))
        }
        _ => None,
    };
    let resume = match (plan.kind, plan.fault_at_s) {
        (Kind::Panic | Kind::Hang, Some(at)) => Some(resume_figures(sitl, at)),
        _ => None,
    };
    Report {
        resume,
        kind: plan.kind,
        rate: plan.rate,
        seed: plan.seed,
        watchdog_resets: sitl.watchdog_resets,
        flight_boots: sitl.boots.iter().filter(|b| b.end == End::Flight).count(),
        max_altitude_m,
        failsafe_at_s,
        disarmed_at_s: disarm.map(|x| x.t_s),
        disarm_reason,
        disarm_height_m: disarm.map(|x| x.altitude_m),
        touchdown_speed_mps,
        motors_stopped_airborne,
        final_state: final_state(s.last()),
        fault_at_s: plan.fault_at_s,
        fault_end_s: plan.fault_end_s,
        failsafe_delay_s: failsafe_at_s.zip(plan.fault_at_s).map(|(f, a)| f - a),
        recovered_at_s,
        rearmed_motors,
        armed_at_s,
        armings,
        settings_error_at_boot: sitl
            .boots
            .iter()
            .find(|b| b.end == End::Flight)
            .map(|b| b.settings_error),
        battery_warning_at_s: level(BatteryLevel::Warning),
        battery_critical_at_s: level(BatteryLevel::Critical),
        gps: plan.gps,
        wind_mps: plan.wind_mps,
        hold,
        step,
    }
}

/// `x` with `decimals`, never "-0.00" (the ground seen from a hair below).
pub fn fixed(x: f64, decimals: usize) -> String {
    let s = format!("{x:.decimals$}");
    if s.starts_with('-') && s.trim_start_matches(['-', '0', '.']).is_empty() {
        s.trim_start_matches('-').to_owned()
    } else {
        s
    }
}

fn num(v: Option<f64>, decimals: usize) -> String {
    match v {
        Some(x) if x.is_finite() => fixed(x, decimals),
        _ => "null".into(),
    }
}

impl Report {
    /// The fields that only some scenarios carry, as (name, JSON value).
    fn extras(&self) -> Vec<(&'static str, String)> {
        let mut e = Vec::new();
        let h = &self.hold;
        let fault = |e: &mut Vec<_>| {
            e.push(("fault_at_s", num(self.fault_at_s, 3)));
            e.push(("fault_end_s", num(self.fault_end_s, 3)));
        };
        match self.kind {
            Kind::Hover => {}
            Kind::AttitudeStep => {
                let f = self.step.unwrap_or_default();
                e.push(("step_at_s", num(self.fault_at_s, 3)));
                e.push(("target_deg", num(Some(f.target_deg), 1)));
                e.push(("setpoint_arrival_s", num(f.setpoint_arrival_s, 4)));
                e.push(("rolling_s", num(f.rolling_s, 3)));
                e.push(("within_1deg_s", num(f.within_1deg_s, 3)));
                e.push((
                    "within_1deg_from_setpoint_s",
                    num(f.within_1deg_from_setpoint_s, 3),
                ));
                e.push(("overshoot_pct", num(f.overshoot_pct, 1)));
            }
            Kind::LinkCut => {
                e.push(("cut_at_s", num(self.fault_at_s, 3)));
                e.push(("failsafe_delay_s", num(self.failsafe_delay_s, 3)));
                e.push(("gps", self.gps.to_string()));
                if self.gps {
                    e.push(("held_position_drift_m", num(h.held_position_drift_m, 2)));
                    e.push(("altitude_error_max_m", num(h.altitude_error_max_m, 2)));
                }
            }
            Kind::Panic | Kind::Hang => {
                let r = self.resume.unwrap_or_default();
                fault(&mut e);
                e.push(("flight_boots", self.flight_boots.to_string()));
                e.push(("resumed", r.resumed.to_string()));
                e.push(("motors_off_after_s", num(r.motors_off_after_s, 3)));
                e.push(("motors_off_for_s", num(r.motors_off_for_s, 3)));
                e.push(("link_word_after_s", num(r.link_word_after_s, 3)));
                e.push(("drop_m", num(r.drop_m, 2)));
            }
            Kind::PowerCycle => {
                e.push(("power_off_at_s", num(self.fault_at_s, 3)));
                e.push(("power_on_at_s", num(self.fault_end_s, 3)));
                e.push(("flight_boots", self.flight_boots.to_string()));
                e.push(("armings", self.armings.to_string()));
                e.push(("rearmed_motors", self.rearmed_motors.to_string()));
            }
            Kind::HandsetUnplugged => {
                e.push(("input_stopped_at_s", num(self.fault_at_s, 3)));
                e.push(("failsafe_delay_s", num(self.failsafe_delay_s, 3)));
            }
            Kind::ImuStall | Kind::ImuFrozen => {
                fault(&mut e);
                e.push(("armings", self.armings.to_string()));
                e.push(("rearmed_motors", self.rearmed_motors.to_string()));
            }
            Kind::RadioStuckIrq | Kind::RadioBrownout => {
                fault(&mut e);
                e.push(("failsafe_delay_s", num(self.failsafe_delay_s, 3)));
                e.push(("recovered_at_s", num(self.recovered_at_s, 3)));
            }
            Kind::SettingsCorrupt => {
                e.push((
                    "settings_error_at_boot",
                    self.settings_error_at_boot
                        .map_or("null".into(), |b| b.to_string()),
                ));
                e.push(("armed_at_s", num(self.armed_at_s, 3)));
            }
            Kind::LowBattery => {
                e.push(("drain_from_s", num(self.fault_at_s, 3)));
                e.push(("battery_warning_at_s", num(self.battery_warning_at_s, 3)));
                e.push(("battery_critical_at_s", num(self.battery_critical_at_s, 3)));
            }
            Kind::AltitudeHold | Kind::PositionHold | Kind::Loiter => {
                e.push(("gps", self.gps.to_string()));
                e.push(("wind_mps", fixed(self.wind_mps, 1)));
                e.push(("hold_engaged_at_s", num(h.engaged_at_s, 3)));
                e.push(("altitude_error_max_m", num(h.altitude_error_max_m, 2)));
                if self.kind != Kind::AltitudeHold {
                    e.push(("position_error_2sigma_m", num(h.position_error_2sigma_m, 2)));
                }
                if self.kind == Kind::PositionHold {
                    e.push(("position_error_max_m", num(h.position_error_max_m, 2)));
                }
                if self.kind == Kind::Loiter {
                    e.push(("loiter_moved_m", num(h.loiter_moved_m, 2)));
                    e.push(("held_position_drift_m", num(h.held_position_drift_m, 2)));
                }
            }
        }
        e
    }

    /// One JSON object (fields in the README).
    pub fn to_json(&self) -> String {
        let mut o = String::from("{");
        let _ = write!(
            o,
            "\"scenario\":\"{}\",\"rate\":\"{}\",\"seed\":{},\"watchdog_resets\":{{\"flight\":{},\"module\":{}}},\"max_altitude_m\":{},\"failsafe_at_s\":{},\"disarmed_at_s\":{},\"disarm_reason\":{},\"disarm_height_m\":{},\"touchdown_speed_mps\":{},\"motors_stopped_airborne\":{},\"final_state\":\"{}\"",
            self.kind.name(),
            self.rate.name(),
            self.seed,
            self.watchdog_resets.flight,
            self.watchdog_resets.module,
            num(Some(self.max_altitude_m), 2),
            num(self.failsafe_at_s, 3),
            num(self.disarmed_at_s, 3),
            self.disarm_reason
                .map_or("null".into(), |r| format!("\"{r}\"")),
            num(self.disarm_height_m, 2),
            num(self.touchdown_speed_mps, 2),
            self.motors_stopped_airborne,
            self.final_state,
        );
        for (k, v) in self.extras() {
            let _ = write!(o, ",\"{k}\":{v}");
        }
        o.push('}');
        o
    }

    /// A human summary, one `name: value` per line.
    pub fn to_text(&self) -> String {
        let json = self.to_json();
        let body = json.trim_start_matches('{').trim_end_matches('}');
        let mut out = String::new();
        // Split on the top-level commas only (the watchdog object holds one).
        let mut depth = 0;
        let mut field = String::new();
        for c in body.chars() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    let _ = writeln!(out, "{}", field.replace('"', "").replacen(':', ": ", 1));
                    field.clear();
                    continue;
                }
                _ => {}
            }
            field.push(c);
        }
        let _ = writeln!(out, "{}", field.replace('"', "").replacen(':', ": ", 1));
        out
    }
}

#[cfg(test)]
#[path = "report_tests.rs"]
mod tests;
