//! Issue 35's dynamic transmit power on a short walk (chip level, both ends' real
//! applications): the flight side goes from 2 km to 200 km in 20 s, past the range at
//! +20 dBm. Dynamic power keeps LQ ≥ 95 % wherever the fixed maximum had it, sends far
//! less near the module, and is at the maximum where the link ends.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

use taulink_sim::walk::{KEPT_LQ, WalkPlan, WalkReport};
use telemetry::link::RateMode;

#[test]
fn a_walk_past_the_range_keeps_the_lq_of_the_fixed_maximum_on_less_power() {
    let plan = WalkPlan {
        duration_s: 20.0,
        ..WalkPlan::DOCUMENTED
    };
    assert_eq!((plan.rate, plan.ratio, plan.bins), (RateMode::F250, 4, 10));
    let report = WalkReport::run(&plan);
    let (fixed, dynamic) = (&report.fixed.bins, &report.dynamic.bins);
    assert_eq!((fixed.len(), dynamic.len()), (10, 10));
    // The criterion, in every tenth and both directions.
    assert_eq!(report.lq_lost(), Vec::new());
    // The walk reaches beyond the fixed maximum's range: its LQ falls below 95 % (≈ 26 %
    // uplink at 100 km), so the criterion is met where it matters, not vacuously.
    assert!(fixed[8].uplink_lq < KEPT_LQ && fixed[8].downlink_lq < KEPT_LQ);
    assert!(fixed.iter().all(|b| b.module_mw > 99.9));
    // At 6.3 km both ends send at +11 dBm (12.6 mW): the reported RSSI, −90 dBm, is
    // 14 dB over F250's −104 dBm, between the thresholds (+10 up, +20 down).
    for mw in [dynamic[2].module_mw, dynamic[2].flight_mw] {
        assert!((mw - 12.6).abs() < 0.1, "{mw} mW at 6.3 km");
    }
    // From 40 km both are back at +20 dBm, as the fixed maximum.
    for b in &dynamic[6..9] {
        assert!(b.module_mw > 99.9 && b.flight_mw > 99.9, "{b:?}");
    }
    // The saving over the walk: a third at the module, more at the flight side.
    let (module, flight) = report.saved_percent();
    assert!((33.0..34.0).contains(&module), "module saved {module} %");
    assert!(
        (38.5..39.5).contains(&flight),
        "flight side saved {flight} %"
    );
}
