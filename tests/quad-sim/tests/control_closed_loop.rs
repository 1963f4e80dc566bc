//! Closed-loop proof on the per-axis plant (exact ZOH, one-sample output latency, 3 deg/s
//! gyro noise, ±1 saturation, 1 kHz): the LQG with the autotuned costs is at least as fast as
//! the analytic-autotune PID with less overshoot (rate) / none and less noise wander
//! (attitude), over ln β 8–11 and τ 15–50 ms; and the frame-invariant costs give similar
//! responses across β. Responses are the expected ones: the mean over antithetic noise-seed
//! pairs (`closed_loop::ensemble`).

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

use flight_core::control::design::{FrameInvariantCosts, KfNoise, LqrCosts, TorqueCost};
use flight_core::model::AxisModel;
use flight_core::sysid::autotune::{AutotuneSettings, analytic_pid, lqg_costs};
use quad_sim::axis::AxisPlantConfig;
use quad_sim::closed_loop::{
    AxisController, Mode, StepMetrics, autotuned_pid, ensemble, lqg_axis, run_step,
};

const TS: f64 = 0.001;
/// Antithetic seed pairs per experiment (32 runs).
const PAIRS: u64 = 16;

/// The expected response (antithetic mean, see `closed_loop::ensemble`) and the hold wander.
fn expected<C: AxisController>(
    model: &AxisModel,
    make: impl Fn() -> C,
    mode: Mode,
    step: f32,
) -> (StepMetrics, f64) {
    let e = ensemble(&AxisPlantConfig::new(*model), make, mode, step, 1.0, PAIRS);
    (e.mean.metrics(5.0), e.wander_rms)
}

fn lqg_metrics(model: &AxisModel, costs: &LqrCosts, mode: Mode, step: f32) -> StepMetrics {
    expected(
        model,
        || lqg_axis(model, TS, costs, &KfNoise::default(), 1).unwrap(),
        mode,
        step,
    )
    .0
}

#[test]
fn lqg_is_faster_than_autotuned_pid_with_less_overshoot() {
    let mut rows = 0;
    for ln_beta in [8.0f32, 9.0, 10.0, 11.0] {
        for tau in [0.015f32, 0.03, 0.05] {
            let model = AxisModel::new(ln_beta, tau).unwrap();
            let tune = analytic_pid([ln_beta; 3], tau, &AutotuneSettings::default()).unwrap();
            let costs = lqg_costs(&tune).for_beta(model.beta1());
            for (mode, step) in [(Mode::Rate, 100.0f32), (Mode::Attitude, 10.0)] {
                let (p, p_wander) =
                    expected(&model, || autotuned_pid(&model, TS).unwrap(), mode, step);
                let (l, l_wander) = expected(
                    &model,
                    || lqg_axis(&model, TS, &costs, &KfNoise::default(), 1).unwrap(),
                    mode,
                    step,
                );
                println!(
                    "lnβ {ln_beta} τ {tau} {mode:?}: LQG rise {:.1} ms os {:.1e} % settle {:.0} ms wander {l_wander:.4} | PID rise {:.1} ms os {:.1e} % settle {:.0} ms wander {p_wander:.4}",
                    l.rise_time_s * 1e3,
                    l.overshoot_pct,
                    l.settling_time_s * 1e3,
                    p.rise_time_s * 1e3,
                    p.overshoot_pct,
                    p.settling_time_s * 1e3
                );
                assert!(l.rise_time_s <= p.rise_time_s, "LQG slower: {l:?} vs {p:?}");
                assert!(
                    l.settling_time_s <= p.settling_time_s,
                    "LQG settles later: {l:?} vs {p:?}"
                );
                match mode {
                    // The PID overshoots 12.5–12.7 %; the LQG's expected response none
                    // (≤ 3e-6 %, f64 round-off), the weakest frame saturating included.
                    Mode::Rate => assert!(
                        l.overshoot_pct < 1e-4 && p.overshoot_pct > 10.0,
                        "{l:?} {p:?}"
                    ),
                    // The autotune's outer loop (ζo = 1.3) is overdamped, so the PID's
                    // expected response never overshoots (0 exactly) and nothing can be
                    // strictly below it; the LQG's does not either (≤ 6e-8 %). The apparent
                    // 0.03–0.1 % of the plain 32-seed mean was the mean's leftover noise
                    // (σ/√32), which the slower PID escaped by still being 0.5–3 % short of
                    // the setpoint at 1 s. What differs strictly is that noise: the LQG
                    // holds the angle with 0.52–0.62× the PID's wander.
                    Mode::Attitude => {
                        assert!(
                            l.overshoot_pct < 1e-4 && p.overshoot_pct < 1e-4,
                            "{l:?} {p:?}"
                        );
                        assert!(l_wander < 0.7 * p_wander, "{l_wander} vs {p_wander}");
                    }
                }
                assert!(l.final_error_pct.abs() < 0.5, "{l:?}");
                rows += 1;
            }
        }
    }
    assert_eq!(rows, 24);
}

#[test]
fn frame_invariant_costs_give_similar_responses_across_beta() {
    // The seed's β sweep (its τ = e^−3.5 ≈ 30 ms, plus 15 and 50 ms): 30 deg/s rate steps,
    // small enough not to saturate the weakest frame. Expected response over 16 antithetic
    // noise-seed pairs.
    let inv = FrameInvariantCosts::default();
    for tau in [0.015f32, 0.03, 0.05] {
        let mut rises = Vec::new();
        let mut fixed_rate_rises = Vec::new();
        for ln_beta in [8.0f32, 8.5, 9.0, 9.5, 10.0, 10.5, 11.0] {
            let model = AxisModel::new(ln_beta, tau).unwrap();
            let m = lqg_metrics(&model, &inv.for_beta(model.beta1()), Mode::Rate, 30.0);
            assert!(m.overshoot_pct < 2.5, "lnβ {ln_beta} τ {tau}: {m:?}");
            rises.push(m.rise_time_s);
            // Only q3 = β·q4 scaled, q_rate fixed at its ln β 9.5 value: not invariant.
            let fixed = LqrCosts {
                q_angle: 1.0,
                q_rate: inv.q2_rate / 9.5f64.exp(),
                q_torque: TorqueCost::PerBeta(inv.q4_torque),
            };
            fixed_rate_rises.push(lqg_metrics(&model, &fixed, Mode::Rate, 30.0).rise_time_s);
        }
        let spread = |v: &[f64]| {
            v.iter().cloned().fold(0.0, f64::max) / v.iter().cloned().fold(f64::MAX, f64::min)
        };
        println!(
            "τ {tau}: invariant rises {rises:?} (spread {:.2}); q3 = βq4 only: {fixed_rate_rises:?} (spread {:.2})",
            spread(&rises),
            spread(&fixed_rate_rises)
        );
        assert!(spread(&rises) < 1.6, "{rises:?}");
        assert!(spread(&fixed_rate_rises) > 2.0, "{fixed_rate_rises:?}");
    }
}

#[test]
fn rate_lqg_rejects_an_input_disturbance_through_the_bias_state() {
    let model = AxisModel::new(10.0, 0.03).unwrap();
    let cfg = AxisPlantConfig {
        input_disturbance: 0.1,
        ..AxisPlantConfig::new(model)
    };
    let costs = FrameInvariantCosts::default().for_beta(model.beta1());
    let mut c = lqg_axis(&model, TS, &costs, &KfNoise::default(), 1).unwrap();
    let r = run_step(&cfg, &mut c, Mode::Rate, 50.0, 3.0);
    let m = r.metrics(5.0);
    // The bias state is the integral action: no steady-state error despite 10 % disturbance.
    assert!(m.final_error_pct.abs() < 1.0, "{m:?}");
    assert!((c.estimate().bias - 0.1).abs() < 0.01, "{:?}", c.estimate());
}

#[test]
fn yaw_with_lag_free_torque_beats_pid() {
    // Yaw: ln β1 7.5 through the motor lag plus ln β2 6 directly from prop acceleration.
    let model = AxisModel::new(7.5, 0.03).unwrap().with_beta2(6.0).unwrap();
    let tune = analytic_pid([7.5; 3], 0.03, &AutotuneSettings::default()).unwrap();
    let costs = lqg_costs(&tune).for_beta(model.beta1());
    let l = lqg_metrics(&model, &costs, Mode::Rate, 50.0);
    let (p, _) = expected(
        &model,
        || autotuned_pid(&model, TS).unwrap(),
        Mode::Rate,
        50.0,
    );
    println!("yaw: LQG {l:?}\n     PID {p:?}");
    assert!(
        l.rise_time_s <= p.rise_time_s && l.overshoot_pct < p.overshoot_pct,
        "{l:?} {p:?}"
    );
    assert!(
        l.overshoot_pct < 3.0 && l.final_error_pct.abs() < 1.0,
        "{l:?}"
    );
}
