//! The seed's OneShot125 experiment (Tau Labs, January 2015): autotune's identification run
//! three times each with conventional PWM at 400 Hz asynchronous to a 500 Hz sensor loop,
//! OneShot125 synchronous at 500 Hz and at 1 kHz; the identified motor time constant τ per
//! run; a one-way ANOVA for an effect of the output type; the reduction of τ in percent.
//!
//! The frame is one true airframe (the same motors, τ and β) in every condition; only the
//! output path differs ([`crate::esc`]). The identification EKF is flight-core's, told no
//! output delay as the seed's EKF had none: whatever delay the output path adds shows up in
//! the identified τ, which is what the seed measured.

use crate::closed_loop::PidAxis;
use crate::esc::{EscConfig, EscPlant, OutputTiming};
use crate::stats::{Anova, mean_std, one_way_anova};
use flight_core::control::pid::{AttitudePid, Pid};
use flight_core::model::{AxisModel, ModelError};
use flight_core::sysid::autotune::{AutotuneSettings, analytic_pid};
use flight_core::sysid::shake::Shake;
use flight_core::sysid::{SysidConfig, SystemIdentifier};
use serde::Serialize;
use sim_plot::{Figure, Panel, Series};
use std::path::PathBuf;

/// One experimental condition.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Condition {
    /// Short name (JSON key, plot label).
    pub name: &'static str,
    /// The output path.
    pub timing: OutputTiming,
    /// Sensor (and control) loop rate, Hz.
    pub loop_hz: u32,
}

/// The seed's three conditions, the reference (PWM) first.
pub const CONDITIONS: [Condition; 3] = [
    Condition {
        name: "PWM 400 Hz async, 500 Hz loop",
        timing: OutputTiming::PwmAsync { rate_hz: 400 },
        loop_hz: 500,
    },
    Condition {
        name: "OneShot125 sync, 500 Hz",
        timing: OutputTiming::OneShot125Sync,
        loop_hz: 500,
    },
    Condition {
        name: "OneShot125 sync, 1 kHz",
        timing: OutputTiming::OneShot125Sync,
        loop_hz: 1000,
    },
];

/// The simulated frame and the runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OneShotSettings {
    /// Runs per condition (the seed: 3).
    pub runs: usize,
    /// Shake duration per run, s.
    pub seconds: f64,
    /// True roll/pitch ln β (yaw 2.5 lower).
    pub ln_beta: f32,
    /// True motor (ESC + motor + prop) time constant, s.
    pub motor_tau_s: f32,
    /// Gyro noise σ, deg/s.
    pub gyro_noise_dps: f64,
    /// ESC input filter: pulses averaged (1 = none).
    pub esc_filter_pulses: usize,
    /// From the gyro sample to the output written, µs.
    pub compute_us: u64,
    /// First noise seed; run r of every condition uses `seed + r`, and the conditions
    /// differ in the seeds' use (the timer phase, the noise), never in the frame.
    pub seed: u64,
}

impl Default for OneShotSettings {
    /// Three 60 s runs per condition of a 250-size frame with fast (KISS-like) ESCs:
    /// ln β 10, τ 4.5 ms (README: why), 5 deg/s gyro noise, no ESC input filter.
    fn default() -> Self {
        Self {
            runs: 3,
            seconds: 60.0,
            ln_beta: 10.0,
            motor_tau_s: 0.0045,
            gyro_noise_dps: 5.0,
            esc_filter_pulses: 1,
            compute_us: 175,
            seed: 1,
        }
    }
}

/// One condition's identified τ.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConditionResult {
    /// The condition.
    pub condition: Condition,
    /// Identified τ per run, s.
    pub tau_s: Vec<f64>,
    /// Mean τ, s.
    pub mean_s: f64,
    /// Sample standard deviation of τ, s.
    pub std_s: f64,
    /// Runs.
    pub n: usize,
    /// Mean τ relative to the first condition (PWM), % less (0 for PWM itself).
    pub reduction_pct: f64,
}

/// The experiment's result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OneShotReport {
    /// What was simulated.
    pub settings: OneShotSettings,
    /// Per condition, in [`CONDITIONS`] order.
    pub conditions: Vec<ConditionResult>,
    /// One-way ANOVA of τ over the output type (all conditions).
    pub anova: Option<Anova>,
    /// The same over the two conditions at 500 Hz only (output type alone, same loop).
    pub anova_500hz: Option<Anova>,
}

/// Identifies τ once: the frame flown by its autotuned PID (attitude on roll/pitch, rate on
/// yaw, as Tau Labs' SYSTEMIDENT mode) with the shake on the outputs, the outputs going
/// through `condition`'s output path, the EKF listening at the loop rate.
///
/// # Errors
/// A model parameter out of range.
pub fn identify_tau(
    condition: &Condition,
    settings: &OneShotSettings,
    seed: u64,
) -> Result<f32, ModelError> {
    let loop_us = 1_000_000 / u64::from(condition.loop_hz.max(1));
    #[allow(clippy::cast_precision_loss)]
    let ts = loop_us as f32 * 1e-6;
    let ln_beta = [settings.ln_beta, settings.ln_beta, settings.ln_beta - 2.5];
    let tau = settings.motor_tau_s;
    let tune = analytic_pid(ln_beta, tau, &AutotuneSettings::default())?;
    let models = [
        AxisModel::new(ln_beta[0], tau)?,
        AxisModel::new(ln_beta[1], tau)?,
        AxisModel::new(ln_beta[2], tau)?,
    ];
    let mut esc = EscConfig::new(condition.timing);
    esc.filter_pulses = settings.esc_filter_pulses;
    esc.compute_us = settings.compute_us;
    let mut plant = EscPlant::new(esc, models, loop_us, settings.gyro_noise_dps, 0.02, seed);
    let mut pids: Vec<PidAxis> = tune
        .rate
        .iter()
        .map(|gains| {
            let rate = Pid::new(*gains, ts);
            PidAxis {
                rate,
                attitude: AttitudePid::new(tune.outer_kp, 0.0, 1000.0, rate, ts),
            }
        })
        .collect();
    let mut cfg = SysidConfig::new(ts);
    // The seed's EKF had no delay term: the output path's delay lands in τ.
    cfg.output_delay_samples = 0;
    #[allow(clippy::cast_possible_truncation)]
    let variance = (10.0 * settings.gyro_noise_dps * settings.gyro_noise_dps).max(1.0) as f32;
    cfg.gyro_variance = variance;
    let mut ekf = SystemIdentifier::new(cfg);
    let mut shake = Shake::new(ts, 0.075);
    let mut gyro = plant.gyro();
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let n = (settings.seconds * f64::from(condition.loop_hz)).round() as usize;
    for _ in 0..n {
        ekf.update(gyro);
        let offsets = shake.next(ekf.ln_beta());
        let angles = plant.angles_deg();
        let mut out = [0.0f32; 3];
        for (i, ((o, pid), (g, offset))) in out
            .iter_mut()
            .zip(pids.iter_mut())
            .zip(gyro.into_iter().zip(offsets))
            .enumerate()
        {
            #[allow(clippy::cast_possible_truncation)]
            let angle = angles.get(i).copied().unwrap_or(0.0) as f32;
            let u = if i == 2 {
                pid.rate.update(0.0, g)
            } else {
                pid.attitude.update(-angle, g)
            };
            *o = (u + offset).clamp(-1.0, 1.0);
        }
        ekf.record_output(out);
        gyro = plant.step(out);
    }
    Ok(ekf.result().tau_s)
}

/// Runs every condition `settings.runs` times; `progress(done, total)` after each run.
///
/// # Errors
/// A model parameter out of range.
pub fn run(
    settings: &OneShotSettings,
    mut progress: impl FnMut(usize, usize),
) -> Result<OneShotReport, ModelError> {
    let total = CONDITIONS.len() * settings.runs;
    let mut done = 0;
    let mut groups: Vec<Vec<f64>> = Vec::new();
    for condition in &CONDITIONS {
        let mut taus = Vec::with_capacity(settings.runs);
        for r in 0..settings.runs {
            let tau = identify_tau(condition, settings, settings.seed.wrapping_add(r as u64))?;
            taus.push(f64::from(tau));
            done += 1;
            progress(done, total);
        }
        groups.push(taus);
    }
    let reference = groups.first().and_then(|g| mean_std(g)).map(|(m, _)| m);
    let conditions = CONDITIONS
        .iter()
        .zip(&groups)
        .map(|(condition, taus)| {
            let (mean_s, std_s) = mean_std(taus).unwrap_or((f64::NAN, f64::NAN));
            let reduction_pct = reference.map_or(f64::NAN, |r| (1.0 - mean_s / r) * 100.0);
            ConditionResult {
                condition: *condition,
                tau_s: taus.clone(),
                mean_s,
                std_s,
                n: taus.len(),
                reduction_pct,
            }
        })
        .collect();
    Ok(OneShotReport {
        settings: *settings,
        conditions,
        anova: one_way_anova(&groups),
        anova_500hz: one_way_anova(groups.get(..2).unwrap_or(&[])),
    })
}

impl OneShotReport {
    /// The human-readable summary the tool prints.
    #[must_use]
    pub fn table(&self) -> String {
        use std::fmt::Write;
        let s = &self.settings;
        let mut out = format!(
            "OneShot125 experiment: true motor τ {:.1} ms, ln β {}, gyro noise {} deg/s, \
             {} s shake, ESC filter {} pulse(s), {} run(s) per condition\n\n",
            s.motor_tau_s * 1e3,
            s.ln_beta,
            s.gyro_noise_dps,
            s.seconds,
            s.esc_filter_pulses,
            s.runs
        );
        let _ = writeln!(
            out,
            "{:<32} {:>3} {:>11} {:>9} {:>10}  runs (ms)",
            "condition", "n", "τ mean ms", "std ms", "reduction"
        );
        for c in &self.conditions {
            let runs: Vec<String> = c.tau_s.iter().map(|t| format!("{:.2}", t * 1e3)).collect();
            let _ = writeln!(
                out,
                "{:<32} {:>3} {:>11.2} {:>9.2} {:>9.1} %  {}",
                c.condition.name,
                c.n,
                c.mean_s * 1e3,
                c.std_s * 1e3,
                c.reduction_pct,
                runs.join(" ")
            );
        }
        for (label, a) in [("all three", self.anova), ("500 Hz only", self.anova_500hz)] {
            if let Some(a) = a {
                let _ = writeln!(
                    out,
                    "\none-way ANOVA ({label}): F({}, {}) = {:.2}, p = {:.2e}",
                    a.df_between, a.df_within, a.f, a.p
                );
            }
        }
        out
    }

    /// The seed's figure: identified τ per condition as a box plot (box = quartiles,
    /// whiskers = range, line = median, crosses = runs).
    #[must_use]
    pub fn box_plot(&self) -> Figure {
        let mut panel = Panel::new("Identified τ per output type", "τ (ms)");
        let all = self
            .conditions
            .iter()
            .flat_map(|c| c.tau_s.iter().map(|t| t * 1e3));
        let (lo, hi) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), t| {
            (l.min(t), h.max(t))
        });
        let span = if hi > lo { hi - lo } else { 1.0 };
        for (i, c) in self.conditions.iter().enumerate() {
            #[allow(clippy::cast_precision_loss)]
            let x = (i + 1) as f64;
            let colour = sim_plot::figure::PALETTE
                .get(i % sim_plot::figure::PALETTE.len())
                .copied()
                .unwrap_or(sim_plot::figure::PALETTE[0]);
            let mut v: Vec<f64> = c.tau_s.iter().map(|t| t * 1e3).collect();
            v.sort_by(f64::total_cmp);
            let q = |p: f64| quantile(&v, p);
            let (lo, q1, med, q3, hi) = (q(0.0), q(0.25), q(0.5), q(0.75), q(1.0));
            let w = 0.25;
            let seg = |name: &str, pts: Vec<(f64, f64)>| {
                Series::new(name.to_string(), pts).colour(colour).width(2)
            };
            panel = panel
                .series(seg(
                    c.condition.name,
                    vec![
                        (x - w, q1),
                        (x + w, q1),
                        (x + w, q3),
                        (x - w, q3),
                        (x - w, q1),
                    ],
                ))
                .series(seg("", vec![(x - w, med), (x + w, med)]).width(3))
                .series(seg("", vec![(x, q3), (x, hi)]))
                .series(seg("", vec![(x, q1), (x, lo)]))
                .series(seg("", vec![(x - w / 2.0, hi), (x + w / 2.0, hi)]))
                .series(seg("", vec![(x - w / 2.0, lo), (x + w / 2.0, lo)]));
            // Each run as a cross beside its box.
            let (cx, dx, dy) = (x + w + 0.1, 0.03, 0.012 * span);
            for t in &v {
                panel = panel
                    .series(seg("", vec![(cx - dx, t - dy), (cx + dx, t + dy)]).width(1))
                    .series(seg("", vec![(cx - dx, t + dy), (cx + dx, t - dy)]).width(1));
            }
        }
        // Room at both ends of the condition axis.
        panel = panel.series(Series::new("", vec![(0.4, f64::NAN), (3.6, f64::NAN)]));
        let title = match self.anova {
            Some(a) => format!(
                "OneShot125 vs PWM: identified motor τ (ANOVA F = {:.1}, p = {:.1e})",
                a.f, a.p
            ),
            None => "OneShot125 vs PWM: identified motor τ".to_string(),
        };
        Figure::new(title)
            .x_label(
                "condition (1 = PWM 400 Hz async, 2 = OneShot125 500 Hz, 3 = OneShot125 1 kHz)",
            )
            .panel(panel)
    }
}

/// Linear-interpolated quantile of sorted values (NaN when empty).
fn quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    #[allow(clippy::cast_precision_loss)]
    let pos = p.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let i = pos.floor() as usize;
    let frac = pos - pos.floor();
    let a = sorted.get(i).copied().unwrap_or(f64::NAN);
    let b = sorted.get(i + 1).copied().unwrap_or(a);
    a + frac * (b - a)
}

/// The tool's arguments: `oneshot` here, and `flight-sitl oneshot-experiment` can embed
/// them as a subcommand's (`#[command(subcommand)]` with `OneShotArgs` as its `Args`).
#[derive(Debug, Clone, clap::Args)]
pub struct OneShotArgs {
    /// Runs per condition (the seed: 3).
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u32).range(2..=100))]
    pub runs: u32,
    /// Shake duration per run, seconds of simulated flight.
    #[arg(long, value_name = "S", default_value_t = 60.0, value_parser = crate::cli::duration)]
    pub seconds: f64,
    /// ESC input filter: average of the last N pulses (1 = none).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub esc_filter: u32,
    /// True motor time constant, seconds.
    #[arg(long, value_name = "S", default_value_t = 0.0045, value_parser = crate::cli::tau)]
    pub tau: f64,
    /// First noise seed.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed: u64,
    /// Print the report as JSON instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Draw the box plot into DIR/oneshot.png.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs the experiment for a command line and prints the table or the JSON (and draws
/// the plot): the one function a CLI calls.
///
/// # Errors
/// A model parameter out of range, or the plot cannot be written.
pub fn run_cli(args: &OneShotArgs) -> Result<OneShotReport, Box<dyn std::error::Error>> {
    #[allow(clippy::cast_possible_truncation)]
    let settings = OneShotSettings {
        runs: args.runs as usize,
        seconds: args.seconds,
        esc_filter_pulses: args.esc_filter as usize,
        motor_tau_s: args.tau as f32,
        seed: args.seed,
        ..OneShotSettings::default()
    };
    let total = CONDITIONS.len() as u64 * u64::from(args.runs);
    let bar = sim_plot::progress::bar(
        total,
        "runs",
        sim_plot::progress::wanted(args.quiet, args.json),
    );
    bar.set_message("identifying");
    let report = run(&settings, |done, _| bar.set_position(done as u64));
    bar.finish_and_clear();
    let report = report?;
    if let Some(dir) = &args.plot {
        std::fs::create_dir_all(dir)?;
        let path = dir.join("oneshot.png");
        report.box_plot().save(&path)?;
        if !args.json {
            println!("plot: {}", path.display());
        }
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.table());
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_interpolate() {
        let v = [1.0, 2.0, 4.0];
        assert_eq!(quantile(&v, 0.0), 1.0);
        assert_eq!(quantile(&v, 0.5), 2.0);
        assert_eq!(quantile(&v, 0.75), 3.0);
        assert_eq!(quantile(&v, 1.0), 4.0);
        assert!(quantile(&[], 0.5).is_nan());
    }
}
