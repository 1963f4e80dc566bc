//! The identification EKF's one-time covariance restart, on a noise-free three-axis plant:
//! each parameter's σ falls below `restart_below_sigma`, jumps back to its initial value
//! exactly once, and the filter then converges to the truth from the better point.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

use flight_core::model::{AxisModel, EstimatorMatrices};
use flight_core::sysid::shake::Shake;
use flight_core::sysid::{SysidConfig, SystemIdentifier};

#[test]
fn parameter_covariance_restarts_once_then_converges() {
    let ts = 0.001f32;
    // Truth: roll/pitch ln β 9, yaw 5.5 (Tau Labs' initial yaw 7 is 1.5 above), τ 25 ms.
    let truth = [9.0f32, 9.0, 5.5];
    let plants =
        truth.map(|lb| EstimatorMatrices::<f64>::new(&AxisModel::new(lb, 0.025).unwrap(), 0.001));
    let mut cfg = SysidConfig::new(ts);
    cfg.gyro_variance = 1.0;
    let mut ekf = SystemIdentifier::new(cfg);
    let mut shake = Shake::new(ts, 0.075);
    let (mut w, mut nu) = ([0.0f64; 3], [0.0f64; 3]);
    let mut sigma_yaw = Vec::new();
    for _ in 0..20_000 {
        ekf.update(w.map(|v| v as f32));
        // Open loop: the shake alone (ω drifts, which the model handles exactly).
        let u = shake.next(ekf.ln_beta());
        ekf.record_output(u);
        for k in 0..3 {
            let p = &plants[k];
            let drive = f64::from(u[k]);
            w[k] += p.a_rate_torque * nu[k] + p.b_rate * drive;
            nu[k] = p.e * nu[k] + p.b_torque * drive;
        }
        sigma_yaw.push(ekf.result().sigma_ln_beta[2]);
    }
    // σ of yaw jumps up exactly once, to its initial 1 (the restart happens inside the
    // update whose correction took it below 0.15), and only shrinks otherwise.
    let jumps: Vec<usize> = sigma_yaw
        .windows(2)
        .enumerate()
        .filter(|(_, p)| p[1] > 1.5 * p[0])
        .map(|(i, _)| i)
        .collect();
    assert_eq!(jumps.len(), 1, "{jumps:?}");
    let j = jumps[0];
    assert!(sigma_yaw[j] < 0.3 && (sigma_yaw[j + 1] - 1.0).abs() < 1e-6);
    assert!(sigma_yaw[j + 1..].last().unwrap() < &0.15);
    let r = ekf.result();
    for (got, want) in r.ln_beta.iter().zip(truth) {
        assert!((got - want).abs() < 0.01, "{r:?}");
    }
    assert!((r.tau_s / 0.025 - 1.0).abs() < 0.01, "{r:?}");
}
