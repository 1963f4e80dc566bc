use super::*;

/// F250 at telemetry ratio 4: a report every 16 ms.
const PERIOD_US: u32 = 16_000;
/// F250's sensitivity.
const SENS: i16 = -104;

/// Feeds a report every period from `from_us` to `to_us` (exclusive), each with `rssi`
/// (margin over sensitivity, dB) and `lq`; returns the steps after each update.
fn run(pc: &mut PowerControl, from_us: u64, to_us: u64, margin: i16, lq: u8) -> Vec<(u64, u8)> {
    let mut out = Vec::new();
    let mut t = from_us;
    while t < to_us {
        let report = LinkReport {
            rssi_dbm: i8::try_from(SENS + margin).unwrap(),
            lq_percent: lq,
        };
        out.push((t, pc.update(&input(t, Some((report, t))))));
        t += u64::from(PERIOD_US);
    }
    out
}

fn input(now_us: u64, report: Option<(LinkReport, u64)>) -> PowerInput {
    PowerInput {
        now_us,
        rate: RateMode::F250,
        connected: true,
        report,
        report_period_us: PERIOD_US,
    }
}

/// When the step first became `step`.
fn first_at(steps: &[(u64, u8)], step: u8) -> Option<u64> {
    steps.iter().find(|(_, s)| *s == step).map(|(t, _)| *t)
}

#[test]
fn sensitivity_is_the_simulators_model_rounded() {
    for rate in RateMode::ALL {
        let model = -121.0 + 10.0 * (f64::from(rate.bit_rate_bps()) / 2_400.0).log10();
        assert_eq!(rate.sensitivity_dbm(), model.round() as i16, "{rate}");
    }
    assert_eq!(RateMode::F250.sensitivity_dbm(), SENS);
}

#[test]
fn a_strong_link_lowers_one_step_a_second_to_the_lowest() {
    let mut pc = PowerControl::new(7, true);
    let steps = run(&mut pc, 0, 9_000_000, 40, 100);
    // The margin holds from the first report at 0: a step down each whole second after.
    assert_eq!(first_at(&steps, 6), Some(1_008_000));
    assert_eq!(first_at(&steps, 5), Some(2_016_000));
    assert_eq!(first_at(&steps, 1), Some(6_048_000));
    assert_eq!(first_at(&steps, 0), Some(7_056_000));
    assert_eq!(pc.step(), 0);
}

#[test]
fn between_the_thresholds_the_step_holds() {
    let mut pc = PowerControl::new(7, true);
    let _ = run(&mut pc, 0, 3_100_000, 25, 100);
    assert_eq!(pc.step(), 4, "three seconds of a 25 dB margin: 7 → 4");
    // 15 dB: neither raise (< 10) nor lower (≥ 20).
    let steps = run(&mut pc, 3_100_000, 13_100_000, 15, 100);
    assert!(steps.iter().all(|(_, s)| *s == 4));
}

#[test]
fn a_weak_margin_raises_a_step_per_eight_reports() {
    let mut pc = PowerControl::new(7, true);
    let _ = run(&mut pc, 0, 4_100_000, 30, 100);
    assert_eq!(pc.step(), 3);
    // 8 dB margin: up one step, then one more after each 8 reports (128 ms).
    let steps = run(&mut pc, 4_100_000, 5_000_000, 8, 100);
    assert_eq!(first_at(&steps, 4), Some(4_100_000));
    assert_eq!(first_at(&steps, 5), Some(4_228_000));
    assert_eq!(first_at(&steps, 6), Some(4_356_000));
    assert_eq!(first_at(&steps, 7), Some(4_484_000));
    assert_eq!(pc.step(), 7, "never above the maximum");
}

#[test]
fn an_lq_below_95_raises_even_on_a_good_rssi() {
    let mut pc = PowerControl::new(7, true);
    let _ = run(&mut pc, 0, 3_100_000, 30, 100);
    assert_eq!(pc.step(), 4);
    let steps = run(&mut pc, 3_100_000, 3_200_000, 30, 90);
    assert_eq!(first_at(&steps, 5), Some(3_100_000));
    // 95 %: not raised, and not lowered either (below 98 %).
    let steps = run(&mut pc, 3_200_000, 6_200_000, 30, 95);
    assert!(steps.iter().all(|(_, s)| *s == 5));
}

#[test]
fn an_lq_drop_goes_to_the_maximum_at_once() {
    let mut pc = PowerControl::new(7, true);
    let _ = run(&mut pc, 0, 5_100_000, 30, 100);
    assert_eq!(pc.step(), 2);
    let steps = run(&mut pc, 5_100_000, 5_116_000, 30, 79);
    assert_eq!(steps, vec![(5_100_000, 7)]);
    // Back down no sooner than a second after.
    let steps = run(&mut pc, 5_116_000, 6_200_000, 30, 100);
    assert_eq!(first_at(&steps, 6), Some(6_124_000));
}

#[test]
fn missed_reports_go_to_the_maximum() {
    let mut pc = PowerControl::new(7, true);
    let _ = run(&mut pc, 0, 5_100_000, 30, 100);
    assert_eq!(pc.step(), 2);
    let last = LinkReport {
        rssi_dbm: 0,
        lq_percent: 100,
    };
    // The last report arrived at 5 084 000: three periods later it still counts ...
    assert_eq!(pc.update(&input(5_132_000, Some((last, 5_084_000)))), 2);
    // ... and one microsecond more is a streak of three missed.
    assert_eq!(pc.update(&input(5_132_001, Some((last, 5_084_000)))), 7);
}

#[test]
fn not_connected_or_no_report_is_the_maximum() {
    let mut pc = PowerControl::new(7, true);
    let _ = run(&mut pc, 0, 3_100_000, 30, 100);
    assert_eq!(pc.step(), 4);
    let report = LinkReport {
        rssi_dbm: -60,
        lq_percent: 100,
    };
    let lost = PowerInput {
        connected: false,
        ..input(3_100_000, Some((report, 3_100_000)))
    };
    assert_eq!(pc.update(&lost), 7);
    let mut fresh = PowerControl::new(5, true);
    assert_eq!(fresh.update(&input(0, None)), 5);
}

#[test]
fn the_set_maximum_caps_every_step() {
    let mut pc = PowerControl::new(4, true);
    assert_eq!(pc.step(), 4);
    let _ = run(&mut pc, 0, 2_100_000, 30, 100);
    assert_eq!(pc.step(), 2);
    let steps = run(&mut pc, 2_100_000, 3_000_000, 0, 100);
    assert!(steps.iter().all(|(_, s)| *s <= 4));
    assert_eq!(pc.step(), 4);
    // A lower maximum applies at once; more than 7 is 7.
    pc.configure(1, true);
    assert_eq!(pc.step(), 1);
    assert_eq!(PowerControl::new(9, true).max(), 7);
}

#[test]
fn fixed_power_is_the_maximum_whatever_the_link() {
    let mut pc = PowerControl::new(6, false);
    let steps = run(&mut pc, 0, 5_000_000, 40, 100);
    assert!(steps.iter().all(|(_, s)| *s == 6));
    // Turned on, it follows the link; turned off again, back to the maximum at once.
    pc.configure(6, true);
    let _ = run(&mut pc, 5_000_000, 7_100_000, 40, 100);
    assert_eq!(pc.step(), 4);
    pc.configure(6, false);
    assert_eq!(pc.step(), 6);
}
