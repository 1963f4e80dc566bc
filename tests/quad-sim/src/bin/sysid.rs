//! `sysid --ln-beta1 10 --tau 0.03 [...]`: shakes a simulated frame, runs the flight-core
//! identification EKF and prints the identified parameters, their confidence and the
//! autotune results as JSON. `sysid --help` lists the flags; the README describes the JSON.

use clap::Parser;
use flight_core::sysid::autotune::{AutotuneSettings, analytic_pid, lqg_costs};
use quad_sim::cli::{duration, ln_beta, non_negative, sample_period, tau};
use quad_sim::identify::SysidExperiment;
use serde_json::json;
use std::process::ExitCode;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// Shake a simulated frame (three per-axis plants sharing τ) under the autotuned PID, identify
/// it with the flight-core identification EKF, and print the identified parameters, their
/// confidence and the autotune results as JSON.
#[derive(Parser, Debug)]
#[command(
    name = "sysid",
    version,
    after_help = "Examples:
  sysid --ln-beta1 10 --tau 0.03
  sysid --ln-beta1 9 --tau 0.05 --gyro-noise 1 --duration 30 --seed 7
  sysid --ln-beta1 10 --tau 0.03 --ekf-delay 0     the EKF told no output delay: τ biased

A progress bar runs on stderr when it is a terminal (not with --quiet).
Exit status: 0 on success, 1 if the experiment fails, 2 for a command-line error."
)]
struct Cli {
    /// True roll ln β (natural log of the authority, (deg/s²) per unit of output), 0..=20.
    #[arg(long, value_name = "L", value_parser = ln_beta)]
    ln_beta1: f64,
    /// True motor time constant τ, seconds (0.001..=1).
    #[arg(long, value_name = "S", value_parser = tau)]
    tau: f64,
    /// True pitch ln β (default: the roll value).
    #[arg(long, value_name = "L", value_parser = ln_beta)]
    ln_beta_pitch: Option<f64>,
    /// True yaw ln β (default: roll − 2.5).
    #[arg(long, value_name = "L", value_parser = ln_beta)]
    ln_beta_yaw: Option<f64>,
    /// Gyro noise σ, deg/s.
    #[arg(long, value_name = "DPS", default_value_t = 5.0, value_parser = non_negative)]
    gyro_noise: f64,
    /// Shake duration, seconds of simulated flight (0 < S ≤ 3600; `--seconds` is the same
    /// flag).
    #[arg(long, visible_alias = "seconds", value_name = "S", default_value_t = 60.0, value_parser = duration)]
    duration: f64,
    /// Loop period, seconds (1e-5..=0.1).
    #[arg(long, value_name = "S", default_value_t = 0.001, value_parser = sample_period)]
    ts: f64,
    /// Output delay of the plant, whole samples (0..=50).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=50))]
    latency: u8,
    /// Output delay the EKF is told, samples (default: the true --latency).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(0..=50))]
    ekf_delay: Option<u8>,
    /// Noise seed.
    #[arg(long, value_name = "N", default_value_t = 3)]
    seed: u64,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[allow(clippy::cast_possible_truncation)] // CLI values → f32 model parameters
fn run(a: &Cli) -> Res<serde_json::Value> {
    let ln_beta = a.ln_beta1 as f32;
    let tau = a.tau as f32;
    let mut e = SysidExperiment::new(ln_beta, tau);
    e.ln_beta[1] = a.ln_beta_pitch.map_or(ln_beta, |v| v as f32);
    e.ln_beta[2] = a.ln_beta_yaw.map_or(ln_beta - 2.5, |v| v as f32);
    e.ts_s = a.ts;
    e.gyro_noise_dps = a.gyro_noise;
    e.seconds = a.duration;
    e.latency_samples = a.latency;
    e.seed = a.seed;
    let ekf_delay = a.ekf_delay.unwrap_or(e.latency_samples);
    #[allow(clippy::cast_sign_loss)] // duration ≤ 3600 s, checked by clap
    let bar = sim_plot::progress::bar(
        e.seconds.ceil() as u64,
        "s shaken",
        sim_plot::progress::wanted(a.quiet, false),
    );
    bar.set_message("identifying");
    let r = e.run_with_progress(ekf_delay, |s| bar.set_position(s));
    bar.finish_and_clear();
    let r = r?;
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
    // clap prints --help/--version (exit 0) and usage errors with a suggestion (exit 2).
    let cli = Cli::parse();
    match run(&cli) {
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
