//! Identification proof: 60 s of shaking per frame (1 kHz, 5 deg/s gyro noise, one-sample
//! output latency, a 0.02 input disturbance, closed loop under the frame's PID) recovers
//! ln β within ±0.05 on every axis and τ within ±5 % over ln β 8–11, τ 15–50 ms; and the
//! Tau Labs timing pairing (ignoring the output delay) is measurably biased.

use quad_sim::identify::SysidExperiment;

#[test]
fn shake_identifies_frames_within_tolerance() {
    let mut worst = (0.0f32, 0.0f32);
    for (ln_beta, tau) in [
        (8.0f32, 0.015f32),
        (8.0, 0.05),
        (9.5, 0.03),
        (11.0, 0.015),
        (11.0, 0.05),
    ] {
        let exp = SysidExperiment::new(ln_beta, tau);
        let r = exp.run().unwrap();
        let tau_err = r.tau_s / tau - 1.0;
        println!(
            "lnβ {ln_beta} τ {tau}: {r:?} τ error {:+.2} %",
            tau_err * 100.0
        );
        for (got, want) in r.ln_beta.iter().zip(exp.ln_beta) {
            assert!((got - want).abs() <= 0.05, "lnβ {got} vs {want} ({r:?})");
            worst.0 = worst.0.max((got - want).abs());
        }
        assert!(tau_err.abs() <= 0.05, "τ {} vs {tau}", r.tau_s);
        worst.1 = worst.1.max(tau_err.abs());
        // Confidence values are reported and consistent with the achieved accuracy.
        assert!(
            r.sigma_ln_beta.iter().all(|s| *s > 0.0 && *s < 0.05),
            "{r:?}"
        );
        assert!(r.sigma_ln_tau > 0.0 && r.sigma_ln_tau < 0.05);
        // The tracked noise matches the simulated 5 deg/s gyro within 10 %.
        assert!(
            r.gyro_noise_dps.iter().all(|n| (n - 5.0).abs() < 0.5),
            "{r:?}"
        );
        assert!(r.bias.iter().all(|b| (b - 0.02).abs() < 0.005), "{r:?}");
        assert_eq!(r.samples, 60_000);
    }
    println!(
        "worst |Δlnβ| {:.4}, worst |Δτ/τ| {:.2} %",
        worst.0,
        worst.1 * 100.0
    );
}

#[test]
fn ignoring_the_output_delay_biases_tau() {
    // Plant with two samples of extra latency, EKF told about none: τ absorbs the delay.
    let mut exp = SysidExperiment::new(9.5, 0.03);
    exp.seconds = 30.0;
    exp.latency_samples = 2;
    let right = exp.run().unwrap();
    let mismatched = exp.run_with_ekf_delay(0).unwrap();
    let bias = mismatched.tau_s / 0.03 - 1.0;
    println!(
        "matched τ {:.4}, mismatched τ {:.4} ({:+.1} %)",
        right.tau_s,
        mismatched.tau_s,
        bias * 100.0
    );
    assert!((right.tau_s / 0.03 - 1.0).abs() < 0.05);
    assert!(bias > 0.03, "{mismatched:?}");
}
