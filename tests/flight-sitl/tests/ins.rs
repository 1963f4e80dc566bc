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
use flight_core::pipeline::Source;
use flight_sitl::PilotInput;
use flight_sitl::metrics::{window, worst};

fn indoor() -> flight_core::settings::Settings {
    let mut s = airframe_settings();
    s.set_text("ins.mode", "ins_indoor").unwrap();
    s
}

/// Take-off, hover, then a 2 s roll of 0.3 stick (13.5°) and back level.
fn banking(settings: flight_core::settings::Settings) -> flight_sitl::Sitl {
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
        f64::from(x.out.attitude_deg[0]) - x.truth.euler_deg[0]
    });
    let pitch = worst(&w, |x| {
        f64::from(x.out.attitude_deg[1]) - x.truth.euler_deg[1]
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
    let run = |settings: flight_core::settings::Settings| {
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
