//! LQG axis controller behaviour that needs no plant: the horizon blend is the weighted mix of
//! the two laws, outputs clamp to ±1, a design failure is an error, never NaN gains, and the
//! RTKF predicts with the output the mixer realised when told it.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used)]

use flight_core::control::design::{DesignError, FrameInvariantCosts, KfNoise, design_axis};
use flight_core::control::lqr::{AxisSetpoint, LqgAxis};
use flight_core::model::AxisModel;

fn axis() -> LqgAxis {
    let m = AxisModel::new(10.0, 0.03).unwrap();
    let c = FrameInvariantCosts::default().for_beta(m.beta1());
    let d = design_axis(&m, 0.001, &c, &c, &KfNoise::default()).unwrap();
    LqgAxis::new(&m, 0.001, &d, 0.3)
}

#[test]
fn horizon_blend_mixes_rate_and_attitude_laws() {
    let base = axis();
    let (rate_sp, err) = (2.0, 0.02);
    let out = |sp| {
        let mut a = base;
        a.update(0.5, sp)
    };
    let rate = out(AxisSetpoint::Rate { rate_dps: rate_sp });
    let att = out(AxisSetpoint::Attitude {
        angle_error_deg: err,
    });
    let blend = |w| {
        out(AxisSetpoint::Blend {
            rate_dps: rate_sp,
            angle_error_deg: err,
            attitude_weight: w,
        })
    };
    assert!(
        rate.abs() > 1e-3 && att.abs() > 1e-3 && (rate - att).abs() > 1e-3,
        "{rate} {att}"
    );
    assert!((blend(0.0) - rate).abs() < 1e-6);
    assert!((blend(1.0) - att).abs() < 1e-6);
    assert!((blend(0.25) - (0.75 * rate + 0.25 * att)).abs() < 1e-6);
    // Weights outside [0, 1] are clamped.
    assert!((blend(7.0) - att).abs() < 1e-6);
}

#[test]
fn output_is_clamped_and_design_errors_are_values() {
    let mut a = axis();
    assert_eq!(a.update(0.0, AxisSetpoint::Rate { rate_dps: 1e6 }), 1.0);
    assert_eq!(a.update(0.0, AxisSetpoint::Rate { rate_dps: -1e6 }), -1.0);
    let m = AxisModel::new(10.0, 0.03).unwrap();
    let mut c = FrameInvariantCosts::default().for_beta(m.beta1());
    c.q_rate = -1.0;
    assert_eq!(
        design_axis(&m, 0.001, &c, &c, &KfNoise::default()).unwrap_err(),
        DesignError::BadCost
    );
    let bad_noise = KfNoise {
        r_gyro: f64::INFINITY,
        ..KfNoise::default()
    };
    let c = FrameInvariantCosts::default().for_beta(m.beta1());
    assert_eq!(
        design_axis(&m, 0.001, &c, &c, &bad_noise).unwrap_err(),
        DesignError::BadCost
    );
}

#[test]
fn yaw_direct_term_changes_the_design() {
    // β2 (lag-free yaw torque) gives the LQR a direct path: with it the design trusts the
    // output more and needs less torque feedback than the same β1 without β2.
    let plain = AxisModel::new(7.5, 0.03).unwrap();
    let yaw = plain.with_beta2(6.0).unwrap();
    let c = FrameInvariantCosts::default().for_beta(plain.beta1());
    let n = KfNoise::default();
    let dp = design_axis(&plain, 0.001, &c, &c, &n).unwrap();
    let dy = design_axis(&yaw, 0.001, &c, &c, &n).unwrap();
    assert!(
        dy.rate
            .iter()
            .zip(dp.rate)
            .all(|(a, b)| a.is_finite() && (a - b).abs() > 1e-6 * b.abs())
    );
    assert!(dy.kalman[0] != dp.kalman[0]);
}

#[test]
fn design_never_returns_non_finite_gains() {
    // Extremes around and beyond the validated range: every result is either finite gains
    // or an error value.
    let mut ok = 0;
    for ln_beta in [0.5f32, 4.0, 7.0, 12.0, 16.0, 20.0] {
        for tau in [0.001f32, 0.005, 0.08, 0.5, 1.0] {
            for ts in [1e-5, 1.0 / 8000.0, 1.0 / 400.0, 0.1] {
                let m = AxisModel::new(ln_beta, tau).unwrap();
                let c = FrameInvariantCosts::default().for_beta(m.beta1());
                if let Ok(d) = design_axis(&m, ts, &c, &c, &KfNoise::default()) {
                    let all = d.kalman.iter().chain(&d.rate).chain(&d.attitude);
                    assert!(
                        all.clone().all(|g| g.is_finite()),
                        "{ln_beta} {tau} {ts}: {d:?}"
                    );
                    ok += 1;
                }
            }
        }
    }
    println!("{ok} of 120 extreme designs solved, the rest returned errors");
    assert!(ok > 60, "{ok} of 120 solved");
}

#[test]
fn the_rtkf_predicts_with_the_realised_output() {
    // Two identical axes saturate at +1; one is told the mixer realised only 0.5. The next
    // prediction differs by exactly B·Δu, and the correction by the filter gain.
    let m = AxisModel::new(10.0, 0.03).unwrap();
    let c = FrameInvariantCosts::default().for_beta(m.beta1());
    let d = design_axis(&m, 0.001, &c, &c, &KfNoise::default()).unwrap();
    let mut told = LqgAxis::new(&m, 0.001, &d, 0.3);
    let mut plain = told;
    let sp = AxisSetpoint::Rate { rate_dps: 1000.0 };
    assert_eq!(told.update(0.0, sp), 1.0);
    assert_eq!(plain.update(0.0, sp), 1.0);
    told.set_realised_output(0.5);
    told.update(0.0, sp);
    plain.update(0.0, sp);
    let em = flight_core::model::EstimatorMatrices::<f64>::new(&m, 0.001);
    let [l_rate, l_torque, _] = d.kalman;
    let du = 0.5;
    let d_rate = (plain.estimate().rate_dps - told.estimate().rate_dps) as f64;
    let d_torque = (plain.estimate().torque - told.estimate().torque) as f64;
    let want_rate = em.b_rate * du * (1.0 - l_rate);
    let want_torque = em.b_torque * du - l_torque * em.b_rate * du;
    assert!(
        (d_rate / want_rate - 1.0).abs() < 1e-3,
        "{d_rate} vs {want_rate}"
    );
    assert!(
        (d_torque / want_torque - 1.0).abs() < 1e-3,
        "{d_torque} vs {want_torque}"
    );
    // NaN is ignored; out-of-range values are clamped like the output.
    let before = told;
    told.set_realised_output(f32::NAN);
    assert_eq!(told, before);
}
