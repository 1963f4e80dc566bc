//! Closed-loop proof on the 6-DoF quadrotor (rigid body with gyroscopic coupling, motor lag,
//! one-sample output latency, 3 deg/s gyro noise, motor saturation, quad-X mixer, 1 kHz):
//! LQG vs autotuned PID for roll rate and roll attitude steps, pitch/yaw held.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

use flight_core::control::design::KfNoise;
use flight_core::control::mixer::{Mixer, QUAD_X, ThrustCurve};
use flight_core::control::pid::{AttitudePid, Pid};
use flight_core::model::AxisModel;
use flight_core::sysid::autotune::{AutotuneSettings, analytic_pid, lqg_costs};
use quad_sim::closed_loop::{AxisController, Mode, PidAxis, StepMetrics, StepResponse, lqg_axis};
use quad_sim::quad::{Quad, QuadParams};

const TS: f64 = 0.001;
const SEEDS: u64 = 8;

/// Flies `seconds` with a roll step (`mode`), pitch attitude 0 and yaw rate 0; returns the
/// seed-averaged roll response and the worst |pitch| (deg) and |yaw rate| (deg/s).
fn fly<C: AxisController>(
    params: &QuadParams,
    make: impl Fn(usize) -> C,
    mode: Mode,
    step: f32,
    seconds: f64,
    tell_realised: bool,
) -> (StepMetrics, f64, f64) {
    let mixer = Mixer::new(QUAD_X, ThrustCurve::Linear);
    let n = (seconds / TS) as usize;
    let mut mean = vec![0.0; n];
    let (mut worst_pitch, mut worst_yaw) = (0.0f64, 0.0f64);
    // Antithetic seed pairs: the mean is the expected response (see `closed_loop::ensemble`).
    for (seed, antithetic_noise) in (1..=SEEDS / 2).flat_map(|s| [(s, false), (s, true)]) {
        let p = QuadParams {
            antithetic_noise,
            ..params.clone()
        };
        let mut quad = Quad::new(p, seed);
        let mut ctrl = [make(0), make(1), make(2)];
        let throttle = params.hover_throttle() as f32;
        let mut gyro = quad.sensors().gyro_dps;
        let mut euler = [0.0f64; 3];
        for y in mean.iter_mut() {
            let u = [
                ctrl[0].update(gyro[0], euler[0] as f32, mode, step),
                ctrl[1].update(gyro[1], euler[1] as f32, Mode::Attitude, 0.0),
                ctrl[2].update(gyro[2], 0.0, Mode::Rate, 0.0),
            ];
            let (motors, realised) = mixer.mix_with_applied(throttle, u);
            if tell_realised {
                for (c, r) in ctrl.iter_mut().zip(realised) {
                    c.realised(r);
                }
            }
            let (s, t) = quad.step(TS, &motors);
            gyro = s.gyro_dps;
            euler = t.euler_deg;
            *y += match mode {
                Mode::Rate => t.rate_dps[0],
                Mode::Attitude => t.euler_deg[0],
            } / SEEDS as f64;
            worst_pitch = worst_pitch.max(t.euler_deg[1].abs());
            worst_yaw = worst_yaw.max(t.rate_dps[2].abs());
        }
    }
    let r = StepResponse {
        ts_s: TS,
        step: f64::from(step),
        response: mean,
        output: Vec::new(),
    };
    (r.metrics(5.0), worst_pitch, worst_yaw)
}

#[test]
fn lqg_beats_pid_on_the_six_dof_quad() {
    for (ln_beta, ln_beta_yaw, tau) in [(10.0, 6.5, 0.03), (8.5, 5.5, 0.045)] {
        let params = QuadParams::quad_x(ln_beta, ln_beta_yaw, tau, &QUAD_X);
        let lb = params.ln_beta(&QUAD_X);
        assert!((lb[0] - ln_beta).abs() < 1e-9 && (lb[2] - ln_beta_yaw).abs() < 1e-9);
        // The controllers see the frame as identification would report it.
        let models = lb.map(|l| AxisModel::new(l as f32, tau as f32).unwrap());
        let tune = analytic_pid(
            lb.map(|l| l as f32),
            tau as f32,
            &AutotuneSettings::default(),
        )
        .unwrap();
        let costs = lqg_costs(&tune);
        let make_lqg = |i: usize| {
            lqg_axis(
                &models[i],
                TS,
                &costs.for_beta(models[i].beta1()),
                &KfNoise::default(),
                1,
            )
            .unwrap()
        };
        // Roll, pitch and yaw each get their own β in the shared ωn/τ_d design.
        let make_pid = |i: usize| {
            let rate = Pid::new(tune.rate[i], TS as f32);
            PidAxis {
                rate,
                attitude: AttitudePid::new(tune.outer_kp, 0.0, 1000.0, rate, TS as f32),
            }
        };
        for (mode, step, secs) in [(Mode::Rate, 100.0f32, 0.4), (Mode::Attitude, 10.0, 0.8)] {
            let (l, lp, ly) = fly(&params, make_lqg, mode, step, secs, true);
            let (p, pp, py) = fly(&params, make_pid, mode, step, secs, true);
            // The same LQG predicting with its request instead of what the mixer realised.
            let (u, _, _) = fly(&params, make_lqg, mode, step, secs, false);
            println!(
                "6-DoF lnβ {ln_beta} τ {tau} {mode:?}: LQG rise {:.1} ms os {:.1e} % (pitch ≤ {lp:.2}°, yaw ≤ {ly:.1}°/s) | PID rise {:.1} ms os {:.1e} % (pitch ≤ {pp:.2}°, yaw ≤ {py:.1}°/s) | LQG told the request: rise {:.1} ms os {:.2} %",
                l.rise_time_s * 1e3,
                l.overshoot_pct,
                p.rise_time_s * 1e3,
                p.overshoot_pct,
                u.rise_time_s * 1e3,
                u.overshoot_pct
            );
            assert!(l.rise_time_s < p.rise_time_s, "{l:?} {p:?}");
            match mode {
                // PID 13 %; LQG none.
                Mode::Rate => assert!(
                    l.overshoot_pct < 0.01 && p.overshoot_pct > 10.0,
                    "{l:?} {p:?}"
                ),
                // Neither overshoots (the PID's outer loop is overdamped).
                Mode::Attitude => assert!(
                    l.overshoot_pct < 0.01 && p.overshoot_pct < 0.01,
                    "{l:?} {p:?}"
                ),
            }
            // Told the request, the RTKF over-predicts whenever the mixer scales the demand
            // (gyro noise through the weak yaw axis): overshoot and a slower rate rise.
            assert!(u.overshoot_pct > 0.2, "{u:?}");
            // Off-axis: pitch stays level and yaw still while rolling.
            assert!(lp < 1.5 && ly < 15.0, "pitch {lp} yaw {ly}");
        }
    }
}
