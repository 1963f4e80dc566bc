//! `lqg gains ...` and `lqg step ...`: LQG design and simulated step responses for one axis,
//! JSON on stdout. `lqg --help` and `lqg step --help` list every flag (README: the JSON).

use clap::{Parser, Subcommand, ValueEnum};
use flight_core::control::design::{self, FrameInvariantCosts, KfNoise, LqrCosts, TorqueCost};
use flight_core::model::{AxisModel, EstimatorMatrices, LqrMatrices};
use flight_core::sysid::autotune::{AutotuneSettings, analytic_pid, lqg_costs};
use quad_sim::axis::AxisPlantConfig;
use quad_sim::cli::{CostArgs, ModelArgs, NoiseArgs, duration, non_negative, number_in};
use quad_sim::closed_loop::{
    AxisController, Mode, StepResponse, autotuned_pid, ensemble, lqg_axis, run_step,
};
use serde_json::json;
use sim_plot::PlotArgs;
use std::process::ExitCode;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// LQG design (RTKF + LQR) and simulated closed-loop step responses for one axis of a
/// multirotor; prints JSON on stdout.
#[derive(Parser, Debug)]
#[command(
    name = "lqg",
    version,
    after_help = "Examples:
  lqg gains --ln-beta1 10 --tau 0.03 --ts 0.001
  lqg gains --ln-beta1 10 --tau 0.03 --q 4,0.04,10000 --kf-q 1,1e-5,1e-7 --kf-r 1000
  lqg step --mode rate --step 100 --ln-beta1 10 --tau 0.03 --compare-pid --plot figs
  lqg step --mode attitude --step 10 --ln-beta1 10 --tau 0.03 --pairs 16

Exit status: 0 on success, 1 if the design fails (the message says why), 2 for a
command-line error."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Discretised models, steady-state Kalman gain and rate/attitude LQR gains as JSON.
    Gains {
        #[command(flatten)]
        model: ModelArgs,
        #[command(flatten)]
        costs: CostArgs,
        #[command(flatten)]
        noise: NoiseArgs,
    },
    /// Simulate a closed-loop step on the per-axis plant and report rise time, overshoot,
    /// settling time and final error (JSON), optionally against the autotuned PID.
    #[command(allow_negative_numbers = true)]
    Step(Box<StepArgs>),
}

#[derive(clap::Args, Debug)]
struct StepArgs {
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    costs: CostArgs,
    #[command(flatten)]
    noise: NoiseArgs,
    /// Which loop the step is applied to.
    #[arg(long, value_enum, default_value_t = ModeArg::Rate)]
    mode: ModeArg,
    /// Step size: deg/s in rate mode (default 100), deg in attitude mode (default 10);
    /// |step| ≤ 10000.
    #[arg(long, value_name = "SIZE", value_parser = step_size)]
    step: Option<f64>,
    /// Simulated time, seconds (0 < S ≤ 3600; `--seconds` is the same flag).
    #[arg(long, visible_alias = "seconds", value_name = "S", default_value_t = 1.0, value_parser = duration)]
    duration: f64,
    /// Output delay of the plant, whole samples (0..=50).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=50))]
    latency: u8,
    /// Gyro noise σ, deg/s.
    #[arg(long, value_name = "DPS", default_value_t = 3.0, value_parser = non_negative)]
    gyro_noise: f64,
    /// Constant input disturbance, in units of the ±1 output (-1..=1).
    #[arg(long, value_name = "U", default_value_t = 0.0, value_parser = unit)]
    disturbance: f64,
    /// Noise seed.
    #[arg(long, value_name = "N", default_value_t = 1)]
    seed: u64,
    /// Report the expected response of N antithetic noise-seed pairs instead of one noisy
    /// run (0..=1000).
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = clap::value_parser!(u64).range(0..=1000))]
    pairs: u64,
    /// Settling band, % of the step (0 < B ≤ 100).
    #[arg(long, value_name = "PCT", default_value_t = 2.0, value_parser = band)]
    band: f64,
    /// Also run the analytic-autotune PID on the same plant.
    #[arg(long)]
    compare_pid: bool,
    #[command(flatten)]
    plot: PlotArgs,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum ModeArg {
    /// Rate loop (step in deg/s).
    Rate,
    /// Attitude loop (step in deg).
    Attitude,
}

fn step_size(s: &str) -> Result<f64, String> {
    number_in(s, -10_000.0, 10_000.0)
}

fn unit(s: &str) -> Result<f64, String> {
    number_in(s, -1.0, 1.0)
}

fn band(s: &str) -> Result<f64, String> {
    let v = number_in(s, 0.0, 100.0)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be greater than 0, got {s}"))
    }
}

#[allow(clippy::cast_possible_truncation)] // CLI values → f32 model parameters
fn model(a: &ModelArgs) -> Res<AxisModel> {
    let m = AxisModel::new(a.ln_beta1 as f32, a.tau as f32)?;
    Ok(match a.ln_beta2 {
        Some(l2) => m.with_beta2(l2 as f32)?,
        None => m,
    })
}

/// Costs: `--invariant q1,q2,q4`, or `--q angle,rate,torque [--q4 X]`, else autotuned.
fn costs(a: &CostArgs, m: &AxisModel) -> Res<(LqrCosts, &'static str)> {
    if let Some([q1_angle, q2_rate, q4_torque]) = a.invariant {
        let inv = FrameInvariantCosts {
            q1_angle,
            q2_rate,
            q4_torque,
        };
        return Ok((inv.for_beta(m.beta1()), "frame-invariant"));
    }
    if let Some([q_angle, q_rate, q3]) = a.q {
        let q_torque = match a.q4 {
            Some(q4) => TorqueCost::PerBeta(q4),
            None => TorqueCost::Absolute(q3),
        };
        return Ok((
            LqrCosts {
                q_angle,
                q_rate,
                q_torque,
            },
            "given",
        ));
    }
    let lb = m.ln_beta1;
    let tune = analytic_pid([lb, lb, lb], m.tau_s, &AutotuneSettings::default())?;
    Ok((lqg_costs(&tune).for_beta(m.beta1()), "autotuned"))
}

fn noise(a: &NoiseArgs) -> KfNoise {
    let d = KfNoise::default();
    let [q_rate, q_torque, q_bias] = a.kf_q.unwrap_or([d.q_rate, d.q_torque, d.q_bias]);
    KfNoise {
        q_rate,
        q_torque,
        q_bias,
        r_gyro: a.kf_r.unwrap_or(d.r_gyro),
    }
}

fn cost_json(c: &LqrCosts, m: &AxisModel) -> serde_json::Value {
    json!({"q_angle": c.q_angle, "q_rate": c.q_rate, "q_torque": c.q_torque.q3(m.beta1()),
           "torque_cost": match c.q_torque { TorqueCost::Absolute(_) => "absolute", TorqueCost::PerBeta(_) => "beta*q4" }})
}

fn gains(ma: &ModelArgs, ca: &CostArgs, na: &NoiseArgs) -> Res<serde_json::Value> {
    let m = model(ma)?;
    let ts = ma.ts;
    let (c, source) = costs(ca, &m)?;
    let n = noise(na);
    let d = design::design_axis(&m, ts, &c, &c, &n)?;
    let est = EstimatorMatrices::<f64>::new(&m, ts);
    let lqr = LqrMatrices::<f64>::new(&m, ts);
    Ok(json!({
        "model": {"ln_beta1": m.ln_beta1, "ln_beta2": m.ln_beta2, "beta1": m.beta1(), "beta2": m.beta2(), "tau_s": m.tau_s, "ts_s": ts},
        "costs": cost_json(&c, &m), "costs_source": source,
        "kf_noise": {"q": [n.q_rate, n.q_torque, n.q_bias], "r": n.r_gyro},
        "estimator": {"state": ["rate_dps", "torque", "bias"], "a": est.a(), "b": est.b(), "c": [1.0, 0.0, 0.0]},
        "lqr_model": {"state": ["angle_deg", "rate_dps", "torque"], "a": lqr.a(), "b": lqr.b},
        "kalman_gain": d.kalman,
        "lqr_rate_gain": d.rate,
        "lqr_attitude_gain": d.attitude,
        "riccati_iterations": {"kalman": d.iterations[0], "rate": d.iterations[1], "attitude": d.iterations[2]},
    }))
}

fn step(a: &StepArgs) -> Res<serde_json::Value> {
    let m = model(&a.model)?;
    let ts = a.model.ts;
    let mode = match a.mode {
        ModeArg::Rate => Mode::Rate,
        ModeArg::Attitude => Mode::Attitude,
    };
    let default_step = if mode == Mode::Rate { 100.0 } else { 10.0 };
    #[allow(clippy::cast_possible_truncation)]
    let size = a.step.unwrap_or(default_step) as f32;
    let (seconds, latency, pairs, band) = (a.duration, a.latency, a.pairs, a.band);
    let cfg = AxisPlantConfig {
        model: m,
        ts_s: ts,
        latency_samples: usize::from(latency),
        gyro_noise_dps: a.gyro_noise,
        input_disturbance: a.disturbance,
        seed: a.seed,
        antithetic: false,
    };
    let (c, source) = costs(&a.costs, &m)?;
    let lqg = lqg_axis(&m, ts, &c, &noise(&a.noise), latency)?;
    let (lqg_run, lqg_report) = experiment(&cfg, lqg, mode, size, seconds, pairs, band);
    let mut out = json!({
        "mode": mode, "step": size, "plant": {"ln_beta1": m.ln_beta1, "tau_s": m.tau_s, "ts_s": ts, "latency_samples": latency, "gyro_noise_dps": cfg.gyro_noise_dps},
        "costs": cost_json(&c, &m), "costs_source": source, "antithetic_pairs": pairs,
        "lqg": lqg_report,
    });
    let mut runs = vec![("LQG", lqg_run)];
    if a.compare_pid {
        let pid = autotuned_pid(&m, ts)?;
        let (pid_run, pid_report) = experiment(&cfg, pid, mode, size, seconds, pairs, band);
        if let Some(o) = out.as_object_mut() {
            o.insert("pid".into(), pid_report);
        }
        runs.push(("PID (autotuned)", pid_run));
    }
    if let Some(path) = a.plot.path("step") {
        let refs: Vec<(&str, &StepResponse)> = runs.iter().map(|(n, r)| (*n, r)).collect();
        let (what, unit) = match mode {
            Mode::Rate => ("Rate", "deg/s"),
            Mode::Attitude => ("Attitude", "deg"),
        };
        let title = format!(
            "{what} step of {size} {unit}: ln β1 {}, τ {} ms, {} deg/s gyro noise",
            m.ln_beta1,
            m.tau_s * 1000.0,
            cfg.gyro_noise_dps
        );
        quad_sim::plot::step_figure(&title, unit, &refs).save_as(&path, a.plot.plot_format)?;
        if let Some(o) = out.as_object_mut() {
            o.insert("plot".into(), json!(path));
        }
    }
    Ok(out)
}

/// One noisy run of `ctrl`, or with `pairs` > 0 the expected response of that many
/// antithetic seed pairs (`closed_loop::ensemble`); returns the response and its metrics
/// (plus the noise wander around the expected response).
fn experiment<C: AxisController + Copy>(
    cfg: &AxisPlantConfig,
    ctrl: C,
    mode: Mode,
    step: f32,
    seconds: f64,
    pairs: u64,
    band: f64,
) -> (StepResponse, serde_json::Value) {
    if pairs == 0 {
        let mut c = ctrl;
        let run = run_step(cfg, &mut c, mode, step, seconds);
        let report = json!(run.metrics(band));
        (run, report)
    } else {
        let e = ensemble(cfg, || ctrl, mode, step, seconds, pairs);
        let mut report = json!(e.mean.metrics(band));
        if let Some(o) = report.as_object_mut() {
            o.insert("wander_rms".into(), json!(e.wander_rms));
        }
        (e.mean, report)
    }
}

fn main() -> ExitCode {
    // clap prints --help/--version (exit 0) and usage errors with a suggestion (exit 2).
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Gains {
            model,
            costs,
            noise,
        } => gains(model, costs, noise),
        Command::Step(a) => step(a),
    };
    match result {
        Ok(v) => {
            println!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("lqg: {e}");
            ExitCode::FAILURE
        }
    }
}
