//! `sysid --ln-beta1 10 --tau 0.03 [...]`: shakes a simulated frame, runs the flight-core
//! identification EKF and prints the identified parameters, their confidence and the
//! autotune results as JSON. See tests/quad-sim/README.md.

use flight_core::sysid::autotune::{AutotuneSettings, analytic_pid, lqg_costs};
use quad_sim::cli::Args;
use quad_sim::identify::SysidExperiment;
use serde_json::json;
use std::process::ExitCode;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)] // CLI values
fn run(a: &Args) -> Res<serde_json::Value> {
    let ln_beta = a.required("ln-beta1")? as f32;
    let tau = a.required("tau")? as f32;
    let mut e = SysidExperiment::new(ln_beta, tau);
    e.ln_beta[1] = a.number_or("ln-beta-pitch", f64::from(ln_beta))? as f32;
    e.ln_beta[2] = a.number_or("ln-beta-yaw", f64::from(ln_beta) - 2.5)? as f32;
    e.ts_s = a.number_or("ts", e.ts_s)?;
    e.gyro_noise_dps = a.number_or("gyro-noise", e.gyro_noise_dps)?;
    e.seconds = a.number_or("seconds", e.seconds)?;
    e.latency_samples = a.number_or("latency", f64::from(e.latency_samples))? as u8;
    e.seed = a.number_or("seed", e.seed as f64)? as u64;
    let ekf_delay = a.number_or("ekf-delay", f64::from(e.latency_samples))? as u8;
    let r = e.run_with_ekf_delay(ekf_delay)?;
    let tune = analytic_pid(r.ln_beta, r.tau_s, &AutotuneSettings::default())?;
    let costs = lqg_costs(&tune);
    let errors: Vec<f32> = r
        .ln_beta
        .iter()
        .zip(e.ln_beta)
        .map(|(g, t)| g - t)
        .collect();
    Ok(json!({
        "truth": {"ln_beta": e.ln_beta, "tau_s": tau},
        "experiment": {"ts_s": e.ts_s, "seconds": e.seconds, "gyro_noise_dps": e.gyro_noise_dps, "latency_samples": e.latency_samples, "ekf_delay_samples": ekf_delay, "seed": e.seed},
        "identified": {
            "ln_beta": r.ln_beta, "tau_s": r.tau_s, "bias": r.bias,
            "sigma_ln_beta": r.sigma_ln_beta, "sigma_ln_tau": r.sigma_ln_tau,
            "gyro_noise_dps": r.gyro_noise_dps, "samples": r.samples,
        },
        "error": {"ln_beta": errors, "tau_pct": (r.tau_s / tau - 1.0) * 100.0},
        "autotune": {
            "pid_rate": tune.rate.map(|g| json!({"kp": g.kp, "ki": g.ki, "kd": g.kd, "derivative_tau_s": g.derivative_tau_s})),
            "outer_kp": tune.outer_kp, "natural_frequency_rad_s": tune.natural_frequency_rad_s,
            "lqg_costs": {"q1_angle": costs.q1_angle, "q2_rate": costs.q2_rate, "q4_torque": costs.q4_torque},
        },
    }))
}

fn main() -> ExitCode {
    let words: Vec<String> = std::env::args().skip(1).collect();
    match Args::parse(&words)
        .map_err(Into::into)
        .and_then(|a| run(&a))
    {
        Ok(v) => {
            println!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("sysid: {e}");
            ExitCode::FAILURE
        }
    }
}
