//! The INS flying the frame (`ins.mode ins_indoor`, no GPS): it takes over from the
//! complementary filter on the ground, and its attitude stays as good as the complementary
//! filter's through take-off, hover and a sustained bank that accelerates the frame
//! sideways (where the indoor pseudo-measurement "not moving" is wrong).

#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

mod common;

use common::*;
use flight_app::pipeline::Source;
use flight_sitl::PilotInput;
use flight_sitl::metrics::{window, worst};

fn indoor() -> flight_app::settings::Settings {
    let mut s = airframe_settings();
    s.set_text("ins.mode", "ins_indoor").unwrap();
    s
}

/// Take-off, hover, then a 2 s roll of 0.3 stick (13.5°) and back level.
fn banking(settings: flight_app::settings::Settings) -> flight_sitl::Sitl {
    fly(
        settings,
        12.0,
        pilot(-1.0, |t| PilotInput {
            roll: if (6.0..8.0).contains(&t) { 0.3 } else { 0.0 },
            ..cruise(-1.0)
        }),
    )
}

fn estimate_error(s: &flight_sitl::Sitl, from: f64, to: f64) -> f64 {
    let w = window(&s.samples, from, to);
    let roll = worst(&w, |x| {
        f64::from(x.out.attitude.roll_deg) - x.truth.euler_deg[0]
    });
    let pitch = worst(&w, |x| {
        f64::from(x.out.attitude.pitch_deg) - x.truth.euler_deg[1]
    });
    roll.max(pitch)
}

#[test]
fn the_indoor_ins_flies_a_take_off_hover_and_bank() {
    let ins = banking(indoor());
    let cf = banking(airframe_settings());
    let s = &ins.samples;
    // The INS flew from before arming to the end, never falling back.
    let first_ins = s.iter().find(|x| x.out.estimator == Source::Ins).unwrap();
    println!("INS took over at {:.3} s", first_ins.t_s);
    assert!(first_ins.t_s < 1.0, "{}", first_ins.t_s);
    assert!(
        s.iter()
            .filter(|x| x.t_s > 1.0)
            .all(|x| x.out.estimator == Source::Ins)
    );
    assert!(
        cf.samples
            .iter()
            .all(|x| x.out.estimator == Source::Complementary)
    );
    let (hover_ins, hover_cf) = (
        estimate_error(&ins, 3.0, 6.0),
        estimate_error(&cf, 3.0, 6.0),
    );
    let (bank_ins, bank_cf) = (
        estimate_error(&ins, 6.0, 12.0),
        estimate_error(&cf, 6.0, 12.0),
    );
    println!(
        "worst roll/pitch estimate error: hover INS {hover_ins:.2}° (complementary {hover_cf:.2}°), \
         bank INS {bank_ins:.2}° (complementary {bank_cf:.2}°)"
    );
    assert!(hover_ins < 1.0, "{hover_ins}");
    assert!(bank_ins < 1.5, "{bank_ins}");
    let level = worst(&window(s, 3.0, 6.0), |x| x.truth.euler_deg[0]);
    assert!(level < 2.0, "held level: {level}");
}

#[test]
fn the_indoor_ins_holds_the_attitude_over_a_long_hover_with_a_gyro_bias() {
    // GIVEN a gyro reading 0.5, −0.5, 0.3 °/s off (learnt on the ground in 2.5 s at most)
    let (mut quad, _) = flight_sitl::scenario::default_airframe();
    quad.gyro_bias_dps = [0.5, -0.5, 0.3];
    let run = |settings: flight_app::settings::Settings| {
        flight_sitl::run(flight_sitl::Scenario::new(
            settings,
            quad.clone(),
            40.0,
            pilot(-1.0, |_| cruise(-1.0)),
        ))
    };
    let (ins, cf) = (run(indoor()), run(airframe_settings()));
    // WHEN it hovers for 36 s
    let (e_ins, e_cf) = (
        estimate_error(&ins, 3.0, 40.0),
        estimate_error(&cf, 3.0, 40.0),
    );
    println!(
        "40 s hover, gyro bias: worst roll/pitch estimate error INS {e_ins:.2}°, complementary {e_cf:.2}°"
    );
    // THEN the estimate error stays within 1°
    assert!(e_ins < 1.0, "{e_ins}");
}

// ---- hold modes and the failsafe hold ---------------------------------------------------

use flight_app::supervisor::FlightMode;
use flight_sitl::gps::GpsConfig;

/// Switch low: attitude (take-off), switch high: `mode`; the INS in `ins_mode`.
fn hold_settings(ins_mode: &str, mode: &str) -> flight_app::settings::Settings {
    let mut s = airframe_settings();
    s.set_text("ins.mode", ins_mode).unwrap();
    s.set_text("mode.switch_high", mode).unwrap();
    s
}

/// Take off in attitude mode, at `engage_s` switch high with the sticks centred.
fn hold_flight(
    settings: flight_app::settings::Settings,
    wind_mps: f64,
    gps: Option<GpsConfig>,
    seconds: f64,
    engage_s: f64,
) -> flight_sitl::Sitl {
    let (mut quad, _) = flight_sitl::scenario::default_airframe();
    quad.wind_ned_mps = [wind_mps, 0.0, 0.0];
    let mut scenario = flight_sitl::Scenario::new(
        settings,
        quad,
        seconds,
        pilot(-1.0, move |t| {
            if t < engage_s {
                cruise(-1.0)
            } else {
                PilotInput {
                    throttle: 0.5,
                    ..cruise(1.0)
                }
            }
        }),
    );
    scenario.gps = gps;
    flight_sitl::run(scenario)
}

fn horizontal_from(x: &flight_sitl::Sample, origin: [f64; 3]) -> f64 {
    let p = x.truth.state.position_m;
    (p[0] - origin[0]).hypot(p[1] - origin[1])
}

#[test]
fn altitude_hold_keeps_the_altitude_within_half_a_metre_for_a_minute() {
    // GIVEN the indoor INS (baro, no GPS) and the switch high on altitude hold
    let sitl = hold_flight(
        hold_settings("ins_indoor", "altitude-hold"),
        0.0,
        None,
        70.0,
        6.0,
    );
    let s = &sitl.samples;
    // The switch reaches the flight controller over the link a few ms later.
    let engaged = s
        .iter()
        .find(|x| x.out.mode == FlightMode::AltitudeHold)
        .unwrap();
    assert!((6.0..6.2).contains(&engaged.t_s), "{}", engaged.t_s);
    let start = engaged.altitude_m;
    // WHEN it hovers with the throttle stick centred for 60 s (after 4 s to settle)
    let w = window(s, 10.0, 70.0);
    let dev = worst(&w, |x| x.altitude_m - start);
    println!("altitude hold: engaged at {start:.2} m, worst deviation over 60 s {dev:.2} m");
    // THEN the altitude stays within ±0.5 m
    assert!(start > 1.0, "flying: {start}");
    assert!(dev < 0.5, "{dev}");
}

#[test]
fn position_hold_holds_within_1_5_m_2_sigma_in_a_3_m_s_wind_with_gps_noise() {
    let sitl = hold_flight(
        hold_settings("ins", "position-hold"),
        3.0,
        Some(GpsConfig::default()),
        70.0,
        8.0,
    );
    let s = &sitl.samples;
    let engaged = s
        .iter()
        .find(|x| x.out.mode == FlightMode::PositionHold)
        .unwrap();
    assert!((8.0..8.2).contains(&engaged.t_s), "{}", engaged.t_s);
    assert_eq!(engaged.out.estimator, Source::Ins);
    let origin = engaged.truth.state.position_m;
    let w = window(s, 18.0, 70.0);
    let rms = (w
        .iter()
        .map(|x| horizontal_from(x, origin).powi(2))
        .sum::<f64>()
        / w.len() as f64)
        .sqrt();
    let far = worst(&w, |x| horizontal_from(x, origin));
    let alt = worst(&w, |x| x.altitude_m - engaged.altitude_m);
    println!(
        "position hold, 3 m/s wind, GPS noise: 2σ {:.2} m, worst {far:.2} m, altitude worst {alt:.2} m",
        2.0 * rms
    );
    assert!(2.0 * rms < 1.5, "{}", 2.0 * rms);
}

/// Hover in attitude mode, the link cut at 10 s.
fn cut_at_hover(gps: Option<GpsConfig>) -> flight_sitl::Sitl {
    let (quad, _) = flight_sitl::scenario::default_airframe();
    let mut scenario = flight_sitl::Scenario::new(
        hold_settings("ins", "position-hold"),
        quad,
        50.0,
        pilot(-1.0, |t| PilotInput {
            link_cut: t >= 10.0,
            ..cruise(-1.0)
        }),
    );
    scenario.gps = gps;
    flight_sitl::run(scenario)
}

#[test]
fn a_link_cut_with_a_good_fix_holds_position_then_descends_and_without_one_descends() {
    let held = cut_at_hover(Some(GpsConfig::default()));
    let s = &held.samples;
    let at_cut = s.iter().find(|x| x.out.failsafe).unwrap().clone();
    let origin = at_cut.truth.state.position_m;
    println!(
        "failsafe at {:.2} s, {:.2} m, climbing {:.2} m/s",
        at_cut.t_s, at_cut.altitude_m, at_cut.climb_mps
    );
    // The hold: 30 s from the failsafe (≈ 10.5 s), position and altitude kept.
    let hold = window(s, 13.0, 40.0);
    assert!(hold.iter().all(|x| x.out.failsafe && x.out.armed));
    let drift = worst(&hold, |x| horizontal_from(x, origin));
    let alt = worst(&hold, |x| x.altitude_m - at_cut.altitude_m);
    let end = s.last().unwrap();
    println!(
        "link cut with a fix: drift {drift:.2} m, altitude change {alt:.2} m over the hold; \
         at {:.1} s altitude {:.2} m",
        end.t_s, end.altitude_m
    );
    assert!(drift < 2.0, "{drift}");
    assert!(alt < 1.0, "{alt}");
    // Then it descends (in place).
    assert!(end.altitude_m < at_cut.altitude_m - 2.0 || !end.out.armed);
    // Without a receiver: the descent at once, as before (0.7 m/s once the climb the
    // frame had at the cut is arrested).
    let plain = cut_at_hover(None);
    let alt_at = |t: f64| {
        plain
            .samples
            .iter()
            .find(|x| x.t_s >= t)
            .unwrap()
            .altitude_m
    };
    let (a14, a20) = (alt_at(14.0), alt_at(20.0));
    println!("link cut without a fix: {a14:.2} m at 14 s → {a20:.2} m at 20 s");
    assert!(a20 < a14 - 3.0, "{a14} {a20}");
}
