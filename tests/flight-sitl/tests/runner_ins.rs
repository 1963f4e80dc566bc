//! Acceptance of issue 16's hold modes through the scenario runner, each with factory
//! settings plus the scenario's INS mode and hold mode (`Options::for_kind`):
//! `altitude-hold` within ±0.5 m over 60 s in still air, `position-hold` within 1.5 m (2σ)
//! in a 3 m/s wind with GPS noise, `loiter` moving the held position and keeping the new
//! one, and `link-cut --gps` holding the position at the failsafe, then descending in place,
//! landing and disarming on the ground (`flight_sitl::runner::acceptance::check`).

#![allow(clippy::unwrap_used)]

use flight_sitl::runner::Kind;
use flight_sitl::runner::acceptance::{
    GPS_LINK_CUT_ALTITUDES_M, check, link_cuts_with_fix, scenario,
};

fn accepted(kind: Kind) -> flight_sitl::runner::Report {
    let r = scenario(kind).unwrap().report;
    println!("{}", r.to_json());
    let bad = check(&r);
    assert!(bad.is_empty(), "{}: {bad:?}", kind.name());
    r
}

#[test]
fn altitude_hold_keeps_half_a_metre_for_a_minute() {
    let r = accepted(Kind::AltitudeHold);
    assert!(!r.gps);
    assert!(r.hold.altitude_error_max_m.unwrap() <= 0.5);
}

#[test]
fn position_hold_keeps_1_5_m_2_sigma_in_a_3_m_s_wind() {
    let r = accepted(Kind::PositionHold);
    assert!(r.gps);
    assert_eq!(r.wind_mps, 3.0);
    assert!(r.hold.position_error_2sigma_m.unwrap() <= 1.5);
}

#[test]
fn loiter_moves_the_held_position_and_keeps_the_new_one() {
    let r = accepted(Kind::Loiter);
    assert!(r.hold.loiter_moved_m.unwrap() >= 2.0);
    assert!(r.hold.held_position_drift_m.unwrap() <= 1.5);
}

#[test]
fn a_link_cut_with_a_fix_holds_then_lands_and_disarms_on_the_ground() {
    // From 5 m the cut comes straight after the take-off boost: the hover estimate is the
    // climb's, and the failsafe's altitude hold once looked like a touchdown to the
    // detector (disarmed at 6.7 m). From 10 m the position hold rocked the landed frame
    // and the failsafe never ended.
    let outcomes = link_cuts_with_fix(&GPS_LINK_CUT_ALTITUDES_M).unwrap();
    let mut failed = Vec::new();
    for (altitude, o) in GPS_LINK_CUT_ALTITUDES_M.iter().zip(&outcomes) {
        let r = &o.report;
        println!("link-cut --gps from {altitude} m: {}", r.to_json());
        assert!(r.gps);
        let bad = check(r);
        if !bad.is_empty() {
            failed.push(format!("{altitude} m: {}", bad.join("; ")));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}
