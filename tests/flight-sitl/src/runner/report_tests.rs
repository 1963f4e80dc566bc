//! The figures on synthetic records: every field measured from hand-made samples.

use super::*;
use crate::runner::pilot::PilotPlan;
use crate::scenario::PilotInput;
use crate::world::{Boot, BootCause};
use flight_app::pipeline::LoopOutput;
use flight_app::supervisor::FlightMode;
use quad_sim::quad::{QuadState, Truth};

const TS: f64 = 0.1;

/// A sample at `t_s`: height, climb, armed, failsafe, motors running or stopped.
fn sample(t_s: f64, altitude_m: f64, climb_mps: f64, armed: bool, failsafe: bool) -> Sample {
    Sample {
        t_s,
        pilot: PilotInput::default(),
        out: LoopOutput {
            motors: [Command::Stopped; 4],
            decision: Decision::Steady,
            mode: FlightMode::Attitude,
            mode_changed: false,
            armed,
            failsafe,
            attitude: flight_app::pipeline::Attitude::LEVEL,
            estimator: flight_app::pipeline::Source::Complementary,
        },
        link_up: !failsafe,
        link_sticks: flight_app::supervisor::Sticks::default(),
        truth: Truth {
            state: QuadState {
                position_m: [0.0, 0.0, -altitude_m],
                velocity_mps: [0.0, 0.0, -climb_mps],
                attitude: [1.0, 0.0, 0.0, 0.0],
                rate_rad_s: [0.0; 3],
                motor: vec![0.0; 4],
            },
            euler_deg: [0.0; 3],
            rate_dps: [0.0; 3],
        },
        altitude_m,
        climb_mps,
        battery: BatteryLevel::Ok,
        tone_hz: 0,
        identification: None,
        motors: if armed {
            [Command::Throttle(0.2); 4]
        } else {
            [Command::Stopped; 4]
        },
        imu_reprobe: false,
        imu_fault: None,
        flight_up: true,
        flight_busy: false,
    }
}

fn sitl(samples: Vec<Sample>) -> Sitl {
    Sitl {
        samples,
        ts_s: TS,
        module_rx: Vec::new(),
        handset_tx: Vec::new(),
        settings: flight_app::settings::Settings::default(),
        watchdog_resets: WatchdogResets::default(),
        boots: Vec::new(),
        flight_logs: Vec::new(),
    }
}

fn plan(kind: Kind, fault_at_s: Option<f64>) -> Plan {
    let quad =
        quad_sim::quad::QuadParams::quad_x(10.0, 6.5, 0.03, &flight_app::control::mixer::QUAD_X);
    Plan {
        kind,
        rate: RateMode::M100,
        seed: 3,
        fault_at_s,
        fault_end_s: None,
        hold_from_s: None,
        duration_s: 10.0,
        pilot: PilotPlan::climb(&quad, 0.05),
        gps: false,
        wind_mps: 0.0,
    }
}

/// A link-cut flight: armed at 1 s, up to 10 m, cut at 3 s, failsafe at 3.5 s, down at 1 m/s,
/// touchdown at 0.8 m/s, disarmed on the ground by the touchdown detector.
fn link_cut_record() -> Vec<Sample> {
    let mut v = Vec::new();
    let mut t = 0.0;
    let mut push = |alt: f64, climb: f64, armed: bool, fs: bool, d: Decision| {
        t += TS;
        let mut s = sample(t, alt, climb, armed, fs);
        s.out.decision = d;
        v.push(s);
    };
    push(0.0, 0.0, false, false, Decision::Steady);
    push(0.0, 0.0, true, false, Decision::Armed);
    push(5.0, 5.0, true, false, Decision::Steady);
    push(10.0, 0.0, true, true, Decision::FailsafeEntered);
    push(5.0, -1.0, true, true, Decision::Steady);
    push(0.4, -0.8, true, true, Decision::Steady);
    push(0.0, 0.0, true, true, Decision::Steady);
    push(0.0, 0.0, false, true, Decision::DisarmedFailsafe);
    push(0.0, 0.0, false, true, Decision::Steady);
    v
}

#[test]
fn a_link_cut_record_gives_its_figures() {
    let r = extract(&sitl(link_cut_record()), &plan(Kind::LinkCut, Some(0.3)));
    assert_eq!(r.max_altitude_m, 10.0);
    assert_eq!(r.armed_at_s, Some(0.2));
    assert_eq!(r.armings, 1);
    // Failsafe rises on the 4th sample (0.4 s), 0.1 s after the fault.
    assert!((r.failsafe_at_s.unwrap() - 0.4).abs() < 1e-9);
    assert!((r.failsafe_delay_s.unwrap() - 0.1).abs() < 1e-9);
    assert!((r.disarmed_at_s.unwrap() - 0.8).abs() < 1e-9);
    assert_eq!(r.disarm_reason, Some("failsafe-landed"));
    assert_eq!(r.disarm_height_m, Some(0.0));
    assert_eq!(r.touchdown_speed_mps, Some(0.8));
    assert!(!r.motors_stopped_airborne);
    assert!(!r.rearmed_motors);
    assert_eq!(r.final_state, "disarmed-on-ground");
    assert!(
        crate::runner::acceptance::check(&r).is_empty(),
        "{:?}",
        crate::runner::acceptance::check(&r)
    );
    let json = r.to_json();
    for field in [
        "\"scenario\":\"link-cut\"",
        "\"rate\":\"M100\"",
        "\"seed\":3",
        "\"watchdog_resets\":{\"flight\":0,\"module\":0}",
        "\"max_altitude_m\":10.00",
        "\"failsafe_at_s\":0.400",
        "\"disarmed_at_s\":0.800",
        "\"disarm_height_m\":0.00",
        "\"touchdown_speed_mps\":0.80",
        "\"motors_stopped_airborne\":false",
        "\"final_state\":\"disarmed-on-ground\"",
        "\"failsafe_delay_s\":0.100",
    ] {
        assert!(json.contains(field), "{field} not in {json}");
    }
}

#[test]
fn motors_stopped_in_the_air_and_restarted_without_arming_are_seen() {
    let mut v = link_cut_record();
    // Stopped at 5 m (a disarm in the air)…
    v[4].out.armed = false;
    v[4].motors = [Command::Stopped; 4];
    // …and running again without an Armed decision.
    v[5].out.armed = false;
    let r = extract(&sitl(v), &plan(Kind::ImuStall, Some(0.3)));
    assert!(r.motors_stopped_airborne);
    assert!(r.rearmed_motors);
    // The record shows armed again at 0.7 s with no arming decision: a second arming edge;
    // the last disarm is the one on the ground.
    assert_eq!(r.armings, 2);
    assert_eq!(r.disarm_height_m, Some(0.0));
    let bad = crate::runner::acceptance::check(&r);
    assert!(bad.iter().any(|b| b.contains("restart")), "{bad:?}");
}

#[test]
fn a_reboot_is_a_disarm_and_the_end_state_follows_the_last_sample() {
    let mut v = link_cut_record();
    v.truncate(4);
    let mut off = sample(0.5, 9.0, -1.0, true, false);
    off.flight_up = false;
    off.motors = [Command::Stopped; 4];
    v.push(off);
    let r = extract(&sitl(v.clone()), &plan(Kind::PowerCycle, None));
    assert_eq!(r.disarm_reason, Some("power-off"));
    assert_eq!(r.final_state, "powered-off");
    assert!(r.motors_stopped_airborne);
    assert_eq!(final_state(None), "no-record");
    assert_eq!(
        final_state(Some(&sample(1.0, 2.0, 0.0, true, false))),
        "armed-flying"
    );
    assert_eq!(
        final_state(Some(&sample(1.0, 2.0, 0.0, true, true))),
        "failsafe-descending"
    );
    assert_eq!(
        final_state(Some(&sample(1.0, 0.0, 0.0, true, false))),
        "armed-on-ground"
    );
    assert_eq!(
        final_state(Some(&sample(1.0, 2.0, -3.0, false, false))),
        "disarmed-airborne"
    );
}

#[test]
fn boots_resets_battery_and_recovery_are_reported() {
    let mut v = link_cut_record();
    v[2].battery = BatteryLevel::Warning;
    v[5].battery = BatteryLevel::Critical;
    v[6].out.decision = Decision::ControlRecovered;
    let mut s = sitl(v);
    s.watchdog_resets = WatchdogResets {
        flight: 2,
        module: 1,
    };
    s.boots = vec![
        Boot {
            t_s: 0.0,
            end: End::Flight,
            cause: BootCause::PowerOn,
            settings_error: true,
        },
        Boot {
            t_s: 0.0,
            end: End::Module,
            cause: BootCause::PowerOn,
            settings_error: false,
        },
    ];
    let r = extract(&s, &plan(Kind::RadioBrownout, Some(0.3)));
    assert_eq!(r.flight_boots, 1);
    assert_eq!(r.settings_error_at_boot, Some(true));
    assert!((r.battery_warning_at_s.unwrap() - 0.3).abs() < 1e-9);
    assert!((r.battery_critical_at_s.unwrap() - 0.6).abs() < 1e-9);
    assert!((r.recovered_at_s.unwrap() - 0.7).abs() < 1e-9);
    assert!(
        r.to_json()
            .contains("\"watchdog_resets\":{\"flight\":2,\"module\":1}")
    );
    assert!(r.to_json().contains("\"recovered_at_s\":0.700"));
    let bad = crate::runner::acceptance::check(&r);
    assert!(bad.iter().any(|b| b.contains("watchdog")), "{bad:?}");
    // The text form has one line per top-level field.
    assert!(
        r.to_text()
            .lines()
            .any(|l| l == "watchdog_resets: {flight:2,module:1}")
    );
}

#[test]
fn numbers_never_read_minus_zero() {
    assert_eq!(fixed(-1e-9, 2), "0.00");
    assert_eq!(fixed(-0.0, 3), "0.000");
    assert_eq!(fixed(-0.004, 2), "0.00");
    assert_eq!(fixed(-0.006, 2), "-0.01");
    assert_eq!(fixed(12.345, 1), "12.3");
}

#[test]
fn the_hold_figures_measure_the_truth_against_what_was_held() {
    // GIVEN a loiter: engaged at 10 s at 10 m, pushed north 15–18 s, then settled at
    // 5 m north and wandering ±0.5 m east (and 0.2 m in height) around it
    let timeline = crate::runner::hold::Timeline::of(Kind::Loiter, 5.0);
    assert_eq!(timeline.engage_s, 10.0);
    let push = timeline.push.unwrap();
    assert_eq!((push.from_s, push.to_s), (20.0, 23.0));
    assert_eq!(timeline.measure_from_s, 31.0);
    let mut v = Vec::new();
    for k in 0..600 {
        let t = f64::from(k) * TS;
        let north = ((t - 20.0) / 3.0).clamp(0.0, 1.0) * 5.0;
        let east = if t >= 31.0 && k % 2 == 1 { 0.5 } else { 0.0 };
        let up = if t >= 31.0 && k % 2 == 1 { 10.2 } else { 10.0 };
        let mut s = sample(t, up, 0.0, true, false);
        s.truth.state.position_m = [north, east, -up];
        if t >= 10.05 {
            s.out.mode = FlightMode::Loiter;
        }
        v.push(s);
    }
    // WHEN measured
    let f = crate::runner::hold::measure(&sitl(v), Kind::Loiter, &timeline, 60.0);
    // THEN the engagement is the first loop in the mode, the move is 5 m, the new position
    // held within 0.5 m (2σ: twice the RMS of 0 and 0.5 alternating = 0.71 m), and the
    // height within 0.2 m of the engagement's
    assert!((f.engaged_at_s.unwrap() - 10.1).abs() < 1e-9);
    assert!((f.loiter_moved_m.unwrap() - 5.0).abs() < 1e-9);
    assert!((f.held_position_drift_m.unwrap() - 0.5).abs() < 1e-9);
    let two_sigma = f.position_error_2sigma_m.unwrap();
    assert!(
        (two_sigma - 2.0 * 0.125f64.sqrt()).abs() < 0.01,
        "{two_sigma}"
    );
    assert!((f.altitude_error_max_m.unwrap() - 0.2).abs() < 1e-9);
    // A hold the flight controller never entered has no figures.
    let never = crate::runner::hold::measure(
        &sitl(vec![sample(11.0, 10.0, 0.0, true, false)]),
        Kind::Loiter,
        &timeline,
        60.0,
    );
    assert_eq!(never, crate::runner::hold::Figures::default());
}
