//! Acceptance of issue 13 through the scenario runner: `link-cut` at every rate mode with
//! factory settings from 5, 30 and 60 m — no watchdog reset at either end, the motors never
//! stopped in the air, disarmed on the ground, touchdown ≤ 1.5 m/s
//! (`flight_sitl::runner::acceptance::check`). One test per rate mode, so the four run in
//! parallel; each finds its three cut times in one probe run.

#![allow(clippy::unwrap_used)]

use flight_sitl::runner::acceptance::{LINK_CUT_ALTITUDES_M, check, link_cuts};
use telemetry::link::RateMode;

fn link_cut_at(rate: RateMode) {
    let outcomes = link_cuts(rate, &LINK_CUT_ALTITUDES_M).unwrap();
    let mut failed = Vec::new();
    for (altitude, o) in LINK_CUT_ALTITUDES_M.iter().zip(&outcomes) {
        let r = &o.report;
        println!("{} from {altitude} m: {}", rate.name(), r.to_json());
        // The cut comes at the altitude (the climb reaches it on the sample of the cut).
        let cut = o.plan.fault_at_s.unwrap();
        let at_cut = o.sitl.samples.iter().find(|s| s.t_s >= cut).unwrap();
        assert!(
            (at_cut.altitude_m - altitude).abs() < 0.1,
            "cut at {} m",
            at_cut.altitude_m
        );
        let bad = check(r);
        if !bad.is_empty() {
            failed.push(format!("{altitude} m: {}", bad.join("; ")));
        }
    }
    assert!(failed.is_empty(), "{}: {failed:?}", rate.name());
}

#[test]
fn link_cut_at_l50_lands_and_disarms_on_the_ground() {
    link_cut_at(RateMode::L50);
}

#[test]
fn link_cut_at_m100_lands_and_disarms_on_the_ground() {
    link_cut_at(RateMode::M100);
}

#[test]
fn link_cut_at_f250_lands_and_disarms_on_the_ground() {
    link_cut_at(RateMode::F250);
}

#[test]
fn link_cut_at_f500_lands_and_disarms_on_the_ground() {
    link_cut_at(RateMode::F500);
}
