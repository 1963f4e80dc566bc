//! The seed's OneShot125 experiment in simulation reproduces its finding: OneShot125 lowers
//! the identified motor time constant, significantly (one-way ANOVA p < 0.01), by about a
//! fifth on the default frame. Shorter runs than the tool's (20 s) keep the test quick.

use quad_sim::experiments::oneshot::{OneShotSettings, run};

#[test]
fn oneshot_lowers_the_identified_tau_significantly() {
    let settings = OneShotSettings {
        seconds: 20.0,
        ..OneShotSettings::default()
    };
    let report = run(&settings, |_, _| {}).unwrap();
    println!("{}", report.table());
    let [pwm, os500, os1k] = [0, 1, 2].map(|i| &report.conditions[i]);
    assert_eq!((pwm.n, os500.n, os1k.n), (3, 3, 3));
    // Every OneShot run below every PWM run.
    let slowest_oneshot = os500
        .tau_s
        .iter()
        .chain(&os1k.tau_s)
        .copied()
        .fold(0.0, f64::max);
    let fastest_pwm = pwm.tau_s.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(slowest_oneshot < fastest_pwm, "{}", report.table());
    let anova = report.anova.unwrap();
    assert!(anova.p < 0.01, "{anova:?}");
    assert!(report.anova_500hz.unwrap().p < 0.01);
    for c in [os500, os1k] {
        assert!(
            (12.0..=28.0).contains(&c.reduction_pct),
            "{}: {} %",
            c.condition.name,
            c.reduction_pct
        );
    }
    // The identified τ is the true one plus what the output path adds: never below it.
    assert!(os1k.mean_s > f64::from(settings.motor_tau_s));
}

#[test]
fn an_esc_input_filter_delays_the_slower_pulse_trains_more() {
    let base = OneShotSettings {
        seconds: 20.0,
        runs: 2,
        ..OneShotSettings::default()
    };
    let plain = run(&base, |_, _| {}).unwrap();
    let filtered = run(
        &OneShotSettings {
            esc_filter_pulses: 4,
            ..base
        },
        |_, _| {},
    )
    .unwrap();
    // Averaging four pulses adds 1.5 pulse periods of delay: 3.75 ms at 400 Hz, 3 ms at
    // 500 Hz, 1.5 ms at 1 kHz — so the 1 kHz loop gains most from OneShot then.
    let added: Vec<f64> = plain
        .conditions
        .iter()
        .zip(&filtered.conditions)
        .map(|(p, f)| f.mean_s - p.mean_s)
        .collect();
    assert!(added.iter().all(|a| *a > 0.0), "{added:?}");
    assert!(added[0] > added[1] && added[1] > added[2], "{added:?}");
}
