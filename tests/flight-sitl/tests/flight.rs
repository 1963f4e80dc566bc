//! Flying: take off and hold attitude, roll-rate steps (PID, LQG), an attitude step, and
//! horizon mode — each through the link from the simulated module.

#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

mod common;

use common::*;
use flight_app::supervisor::{Decision, FlightMode};
use flight_sitl::PilotInput;
use flight_sitl::metrics::{step, window, worst};

#[test]
fn takes_off_and_holds_attitude() {
    let sitl = fly(airframe_settings(), 8.0, pilot(-1.0, |_| cruise(-1.0)));
    let s = &sitl.samples;
    let armed_at = s
        .iter()
        .find(|x| x.out.decision == Decision::Armed)
        .unwrap();
    println!("armed at {:.3} s", armed_at.t_s);
    assert!(
        (1.5..2.0).contains(&armed_at.t_s),
        "gesture held 1 s after sync"
    );
    assert_eq!(armed_at.out.mode, FlightMode::Attitude);
    // On the ground before take-off, armed: idle, not moving.
    let ground = window(s, 2.1, 2.5);
    assert!(ground.iter().all(|x| x.altitude_m < 0.01));
    let flight = window(s, 3.0, 8.0);
    let roll = worst(&flight, |x| x.truth.euler_deg[0]);
    let pitch = worst(&flight, |x| x.truth.euler_deg[1]);
    let est = worst(&flight, |x| {
        f64::from(x.out.attitude.roll_deg) - x.truth.euler_deg[0]
    });
    let alt = s.last().unwrap().altitude_m;
    println!(
        "take-off: worst roll {roll:.2}°, pitch {pitch:.2}°, estimate error {est:.2}°, altitude {alt:.2} m"
    );
    assert!(roll < 2.0 && pitch < 2.0, "{roll} {pitch}");
    assert!(est < 1.0, "{est}");
    assert!(alt > 2.0, "climbed: {alt}");
    assert!(s.iter().all(|x| x.link_up || x.t_s < 0.5), "link stayed up");
}

/// A roll stick step of 0.2 in a rate mode: 0.7·0.2 + 0.3·0.008 = 0.1424 → 102.5 deg/s.
fn rate_step(mode_switch: f32) -> (flight_sitl::metrics::Step, f64) {
    let sitl = fly(
        airframe_settings(),
        5.6,
        pilot(mode_switch, move |t| PilotInput {
            roll: if (5.0..5.5).contains(&t) { 0.2 } else { 0.0 },
            ..cruise(mode_switch)
        }),
    );
    let w = window(&sitl.samples, 5.0, 5.5);
    let pitch = worst(&w, |x| x.truth.rate_dps[1]);
    (step(&w, |x| x.truth.rate_dps[0], 0.0, 102.5), pitch)
}

#[test]
fn follows_roll_rate_steps_with_pid() {
    let (m, cross) = rate_step(0.0);
    println!("rate PID 102.5°/s step: {m:?}, pitch-rate cross-talk {cross:.1}°/s");
    assert!(m.rise_s < 0.06, "{m:?}");
    assert!(m.overshoot_pct < 25.0, "{m:?}");
    assert!((m.final_value - 102.5).abs() < 10.0, "{m:?}");
}

#[test]
fn follows_roll_rate_steps_with_lqg() {
    let (m, cross) = rate_step(1.0);
    println!("rate LQG 102.5°/s step: {m:?}, pitch-rate cross-talk {cross:.1}°/s");
    assert!(m.rise_s < 0.06, "{m:?}");
    assert!(m.overshoot_pct < 10.0, "{m:?}");
    assert!((m.final_value - 102.5).abs() < 5.0, "{m:?}");
}

/// A yaw stick step of 0.4: (0.7·0.4 + 0.3·0.064)·720/2 = 107.7 deg/s; the yaw axis has
/// 30× less authority (ln β 6.5), so it is slower than roll.
fn yaw_step(mode_switch: f32) -> flight_sitl::metrics::Step {
    let sitl = fly(
        airframe_settings(),
        6.0,
        pilot(mode_switch, move |t| PilotInput {
            yaw: if (5.0..6.0).contains(&t) { 0.4 } else { 0.0 },
            ..cruise(mode_switch)
        }),
    );
    let w = window(&sitl.samples, 5.0, 6.0);
    step(&w, |x| x.truth.rate_dps[2], 0.0, 107.712)
}

#[test]
fn follows_yaw_rate_steps_with_pid_and_lqg() {
    let pid = yaw_step(0.0);
    let lqg = yaw_step(1.0);
    println!("yaw 107.7°/s step: PID {pid:?}\n                    LQG {lqg:?}");
    assert!(pid.rise_s < 0.25 && pid.overshoot_pct < 15.0, "{pid:?}");
    assert!(
        lqg.rise_s < pid.rise_s && lqg.overshoot_pct < 5.0,
        "{lqg:?}"
    );
    for m in [pid, lqg] {
        assert!((m.final_value - 107.7).abs() < 8.0, "{m:?}");
    }
}

#[test]
fn reaches_commanded_angles_in_attitude_mode() {
    // Roll stick 1/3 → 15°, for 1 s, then back.
    let sitl = fly(
        airframe_settings(),
        6.5,
        pilot(-1.0, |t| PilotInput {
            roll: if (5.0..6.0).contains(&t) {
                1.0 / 3.0
            } else {
                0.0
            },
            ..cruise(-1.0)
        }),
    );
    let w = window(&sitl.samples, 5.0, 6.0);
    let m = step(&w, |x| x.truth.euler_deg[0], 0.0, 15.0);
    let within = w
        .iter()
        .find(|x| (x.truth.euler_deg[0] - 15.0).abs() < 1.0)
        .map(|x| x.t_s - 5.0)
        .unwrap();
    // The stick's way to the motors (PPM capture, uplink, loop): the first roll rate of
    // 5 °/s.
    let moving = w
        .iter()
        .find(|x| x.truth.rate_dps[0] > 5.0)
        .map(|x| x.t_s - 5.0)
        .unwrap();
    // The setpoint's arrival at the flight controller: the first loop flying the new stick.
    let arrived = w
        .iter()
        .find(|x| x.link_sticks.roll > 0.3)
        .map(|x| x.t_s - 5.0)
        .unwrap();
    let back = window(&sitl.samples, 6.4, 6.5);
    let level = worst(&back, |x| x.truth.euler_deg[0]);
    println!(
        "attitude 15° step: {m:?}, setpoint at the flight controller after {arrived:.4} s, rolling at 5 °/s after {moving:.3} s, within 1° after {within:.3} s from the stick ({:.3} s from the setpoint's arrival), back to {level:.2}° 0.4 s after release",
        within - arrived
    );
    assert!(within < 0.4, "{within}");
    // The stick's way (at F250): the next PPM frame starts (0–22.5 ms by phase), that frame
    // is released once its sync gap is proven (≈ 14 ms), the next uplink latches it (0–8 ms
    // at 1:4), it is on the air and read out (≈ 3 ms), the loop flies it (≤ 1 ms).
    assert!(arrived < 0.05, "{arrived}");
    // From the setpoint's arrival, the loop's own response: as fast as the stick's whole way
    // was when the world handed the channels to the master directly (0.154 s).
    assert!(within - arrived < 0.16, "{within} {arrived}");
    assert!(m.overshoot_pct < 10.0, "{m:?}");
    assert!((m.final_value - 15.0).abs() < 1.0, "{m:?}");
    assert!(level < 2.0, "{level}");
}

#[test]
fn horizon_mode_rolls_on_the_stick_and_levels_when_centred() {
    let mut settings = airframe_settings();
    settings.set_text("mode.switch_mid", "horizon").unwrap();
    // Full right roll for 0.5 s: a rate command at full deflection (horizon weight 0).
    let sitl = fly(
        settings,
        7.5,
        pilot(0.0, |t| PilotInput {
            roll: if (5.0..5.5).contains(&t) { 1.0 } else { 0.0 },
            ..cruise(0.0)
        }),
    );
    let s = &sitl.samples;
    assert!(
        s.iter()
            .filter(|x| x.t_s > 3.0)
            .all(|x| x.out.mode == FlightMode::Horizon)
    );
    let rolling = window(s, 5.0, 5.5);
    let peak_rate = rolling
        .iter()
        .map(|x| x.truth.rate_dps[0])
        .fold(f64::MIN, f64::max);
    let bank = s
        .iter()
        .map(|x| x.truth.euler_deg[0].abs())
        .fold(0.0, f64::max);
    let level = worst(&window(s, 6.5, 7.5), |x| x.truth.euler_deg[0]);
    println!(
        "horizon: peak roll rate {peak_rate:.0}°/s, largest bank {bank:.0}°, 1–2 s after release {level:.2}°"
    );
    // Full deflection = 720 °/s for 0.5 s: a full flip (the Euler roll passes ±180°), then
    // the centred stick is attitude mode again and levels the frame.
    assert!(peak_rate > 500.0, "{peak_rate}");
    assert!(bank > 90.0, "{bank}");
    assert!(level < 3.0, "{level}");
}

#[test]
fn flies_through_a_lossy_link() {
    use flight_sitl::Scenario;
    // 30 % of packets lost at random in both directions: the sticks still arrive (250 Hz
    // uplink), no failsafe, and the 15° attitude step is flown as with a clean link.
    let (quad, settings) = flight_sitl::scenario::default_airframe();
    let sitl = flight_sitl::run(Scenario {
        settings,
        quad,
        seed: 7,
        duration_s: 6.5,
        link_failsafe_ms: 500,
        pilot: Box::new(pilot(-1.0, |t| PilotInput {
            roll: if (5.0..6.0).contains(&t) {
                1.0 / 3.0
            } else {
                0.0
            },
            ..cruise(-1.0)
        })),
        setting_changes: Vec::new(),
        packet_loss: 0.3,
        rate: telemetry::link::RateMode::F250,
        module_settings: None,
        flight_flash: flight_sitl::FlashInjection::Stored,
        gps: None,
    });
    let s = &sitl.samples;
    assert!(
        s.iter().filter(|x| x.t_s > 1.0).all(|x| x.link_up),
        "no failsafe"
    );
    assert!(s.iter().all(|x| !x.out.failsafe));
    let w = window(s, 5.0, 6.0);
    let m = step(&w, |x| x.truth.euler_deg[0], 0.0, 15.0);
    let lq = sitl
        .module_rx
        .iter()
        .rev()
        .find_map(|(_, m)| match m {
            telemetry::messages::Message::LinkStats(l) => Some(*l),
            _ => None,
        })
        .unwrap();
    println!(
        "30 % loss: attitude step {m:?}, flight-side LQ {} %, module-side {} %",
        lq.uplink_lq, lq.downlink_lq
    );
    assert!((60..=85).contains(&lq.uplink_lq), "{lq:?}");
    assert!(
        m.overshoot_pct < 10.0 && (m.final_value - 15.0).abs() < 1.0,
        "{m:?}"
    );
}
