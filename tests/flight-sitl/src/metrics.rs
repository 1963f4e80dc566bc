//! Numbers from a run: step-response rise time and overshoot, worst errors over a window.

use crate::world::Sample;

/// A step response measured on one recorded signal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// 10 → 90 % rise time, s (infinite if never reached).
    pub rise_s: f64,
    /// Peak beyond the step, % of the step.
    pub overshoot_pct: f64,
    /// Mean of the signal over the last quarter of the window.
    pub final_value: f64,
}

/// Measures the response of `signal` over `samples` from `from` (the step's value at the
/// window start) to `to`.
pub fn step(samples: &[&Sample], signal: impl Fn(&Sample) -> f64, from: f64, to: f64) -> Step {
    let span = to - from;
    let norm: Vec<f64> = samples.iter().map(|s| (signal(s) - from) / span).collect();
    let t0 = samples.first().map_or(0.0, |s| s.t_s);
    let at = |level: f64| {
        samples
            .iter()
            .zip(&norm)
            .find(|(_, n)| **n >= level)
            .map_or(f64::INFINITY, |(s, _)| s.t_s - t0)
    };
    let peak = norm.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let tail = norm.get(norm.len() * 3 / 4..).unwrap_or(&[]);
    let final_norm = tail.iter().sum::<f64>() / tail.len().max(1) as f64;
    Step {
        rise_s: at(0.9) - at(0.1),
        overshoot_pct: ((peak - 1.0) * 100.0).max(0.0),
        final_value: from + final_norm * span,
    }
}

/// The samples with `from_s ≤ t < to_s`.
pub fn window(samples: &[Sample], from_s: f64, to_s: f64) -> Vec<&Sample> {
    samples
        .iter()
        .filter(|s| s.t_s >= from_s && s.t_s < to_s)
        .collect()
}

/// The largest |signal| over `samples`.
pub fn worst(samples: &[&Sample], signal: impl Fn(&Sample) -> f64) -> f64 {
    samples.iter().map(|s| signal(s).abs()).fold(0.0, f64::max)
}
