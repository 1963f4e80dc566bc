//! `lqg gains ...` and `lqg step ...`: LQG design and simulated step responses for one axis,
//! JSON on stdout. See tests/quad-sim/README.md for every flag.

use flight_core::control::design::{self, FrameInvariantCosts, KfNoise, LqrCosts, TorqueCost};
use flight_core::model::{AxisModel, EstimatorMatrices, LqrMatrices};
use flight_core::sysid::autotune::{AutotuneSettings, analytic_pid, lqg_costs};
use quad_sim::axis::AxisPlantConfig;
use quad_sim::cli::Args;
use quad_sim::closed_loop::{
    AxisController, Mode, StepResponse, autotuned_pid, ensemble, lqg_axis, run_step,
};
use serde_json::json;
use std::process::ExitCode;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

#[allow(clippy::cast_possible_truncation)] // CLI values → f32 model parameters
fn model(a: &Args) -> Res<AxisModel> {
    let m = AxisModel::new(a.required("ln-beta1")? as f32, a.required("tau")? as f32)?;
    Ok(match a.number("ln-beta2")? {
        Some(l2) => m.with_beta2(l2 as f32)?,
        None => m,
    })
}

/// Costs: `--invariant q1,q2,q4`, or `--q angle,rate,torque [--q4 X]`, else autotuned.
fn costs(a: &Args, m: &AxisModel) -> Res<(LqrCosts, &'static str)> {
    if let Some([q1_angle, q2_rate, q4_torque]) = a.list("invariant")? {
        let inv = FrameInvariantCosts {
            q1_angle,
            q2_rate,
            q4_torque,
        };
        return Ok((inv.for_beta(m.beta1()), "frame-invariant"));
    }
    if let Some([q_angle, q_rate, q3]) = a.list("q")? {
        let q_torque = match a.number("q4")? {
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

fn noise(a: &Args) -> Res<KfNoise> {
    let d = KfNoise::default();
    let [q_rate, q_torque, q_bias] = a.list("kf-q")?.unwrap_or([d.q_rate, d.q_torque, d.q_bias]);
    Ok(KfNoise {
        q_rate,
        q_torque,
        q_bias,
        r_gyro: a.number_or("kf-r", d.r_gyro)?,
    })
}

fn cost_json(c: &LqrCosts, m: &AxisModel) -> serde_json::Value {
    json!({"q_angle": c.q_angle, "q_rate": c.q_rate, "q_torque": c.q_torque.q3(m.beta1()),
           "torque_cost": match c.q_torque { TorqueCost::Absolute(_) => "absolute", TorqueCost::PerBeta(_) => "beta*q4" }})
}

fn gains(a: &Args) -> Res<serde_json::Value> {
    let m = model(a)?;
    let ts = a.number_or("ts", 0.001)?;
    let (c, source) = costs(a, &m)?;
    let n = noise(a)?;
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

fn step(a: &Args) -> Res<serde_json::Value> {
    let m = model(a)?;
    let ts = a.number_or("ts", 0.001)?;
    let mode = match a.text("mode").unwrap_or("rate") {
        "rate" => Mode::Rate,
        "attitude" => Mode::Attitude,
        other => return Err(format!("--mode {other:?}: rate or attitude").into()),
    };
    let default_step = if mode == Mode::Rate { 100.0 } else { 10.0 };
    #[allow(clippy::cast_possible_truncation)]
    let size = a.number_or("step", default_step)? as f32;
    let seconds = a.number_or("seconds", 1.0)?;
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let latency = a.number_or("latency", 1.0)? as u8;
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let seed = a.number_or("seed", 1.0)? as u64;
    let cfg = AxisPlantConfig {
        model: m,
        ts_s: ts,
        latency_samples: usize::from(latency),
        gyro_noise_dps: a.number_or("gyro-noise", 3.0)?,
        input_disturbance: a.number_or("disturbance", 0.0)?,
        seed,
        antithetic: false,
    };
    let (c, source) = costs(a, &m)?;
    let lqg = lqg_axis(&m, ts, &c, &noise(a)?, latency)?;
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let pairs = a.number_or("pairs", 0.0)? as u64;
    let band = a.number_or("band", 2.0)?;
    let (lqg_run, lqg_report) = experiment(&cfg, lqg, mode, size, seconds, pairs, band);
    let mut out = json!({
        "mode": mode, "step": size, "plant": {"ln_beta1": m.ln_beta1, "tau_s": m.tau_s, "ts_s": ts, "latency_samples": latency, "gyro_noise_dps": cfg.gyro_noise_dps},
        "costs": cost_json(&c, &m), "costs_source": source, "antithetic_pairs": pairs,
        "lqg": lqg_report,
    });
    let mut runs = vec![("lqg", lqg_run)];
    if a.has("compare-pid") {
        let pid = autotuned_pid(&m, ts)?;
        let (pid_run, pid_report) = experiment(&cfg, pid, mode, size, seconds, pairs, band);
        if let Some(o) = out.as_object_mut() {
            o.insert("pid".into(), pid_report);
        }
        runs.push(("pid", pid_run));
    }
    if let Some(path) = a.text("plot") {
        let refs: Vec<(&str, &StepResponse)> = runs.iter().map(|(n, r)| (*n, r)).collect();
        quad_sim::plot::step_png(path, &refs)?;
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
    let words: Vec<String> = std::env::args().skip(1).collect();
    let Some((cmd, rest)) = words.split_first() else {
        eprintln!(
            "usage: lqg gains|step --ln-beta1 L --tau S [...] (see tests/quad-sim/README.md)"
        );
        return ExitCode::FAILURE;
    };
    let result = Args::parse(rest)
        .map_err(Into::into)
        .and_then(|a| match cmd.as_str() {
            "gains" => gains(&a),
            "step" => step(&a),
            other => Err(format!("unknown command {other:?}: gains or step").into()),
        });
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
