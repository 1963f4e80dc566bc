//! The identification excitation ("shake", `control/LQG.md` §5): square offsets added to the
//! stabilising controller's output in an 8-phase cycle yaw+, roll+, yaw−, roll−, yaw+,
//! pitch+, yaw−, pitch−. Roll and pitch each get one + and one − pulse per cycle and yaw four
//! alternating ones, so every axis has zero mean excitation.
//!
//! Amplitude follows Tau Labs: exp(7.1 − ln β̂) from the *current* estimate, so a weak frame
//! is pushed harder, capped at 0.25 (roll/pitch) and 0.7 (yaw; Tau Labs 0.45).
//!
//! Why 0.7 for yaw: on a weak yaw axis (ln β 5, I_yaw ≈ 3.6·I_roll) the cap binds and the
//! yaw rate PID feeds gyro noise into the output; the filter's state error is correlated
//! with that noise, which biases ln β up in proportion to (noise feedback)/(excitation).
//! Measured on the 6-DoF quad at 5 deg/s, 60 s, 4 seeds × 3 τ: +0.018…+0.052 with 0.45,
//! +0.012…+0.027 with 0.7, +0.000…+0.017 with 1.0. 0.7 keeps 0.3 of the motor range for
//! roll/pitch during a yaw pulse; frames with ln β_yaw > 7.46 are below the cap anyway.

use core::num::NonZeroU32;

/// Axis index order used throughout identification: roll, pitch, yaw.
const PHASES: [(usize, f32); 8] = [
    (2, 1.0),
    (0, 1.0),
    (2, -1.0),
    (0, -1.0),
    (2, 1.0),
    (1, 1.0),
    (2, -1.0),
    (1, -1.0),
];

/// ln of the amplitude numerator (Tau Labs `stabilization.c`).
const LN_AMPLITUDE_SCALE: f32 = 7.1;
/// Amplitude caps, roll/pitch and yaw.
const CAPS: [f32; 3] = [0.25, 0.25, 0.7];

/// The shake generator. Both divisors are `NonZeroU32`: a phase of `u32::MAX / 8` samples or
/// more would wrap the cycle length `8 × phase` to a multiple of 2³² (0 at 2²⁹), and the
/// counter's `%` would divide by zero; the phase is capped below that instead.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shake {
    phase_samples: NonZeroU32,
    cycle_samples: NonZeroU32,
    counter: u32,
}

/// The longest phase, samples: the cycle (8 phases) still fits a `u32`.
const MAX_PHASE_SAMPLES: u32 = u32::MAX / 8;

impl Shake {
    /// A shake whose phases last `phase_s` (Tau Labs: 75 ms) at loop period `ts_s`.
    pub fn new(ts_s: f32, phase_s: f32) -> Self {
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)] // saturating cast
        let phase = (libm::roundf(phase_s / ts_s) as u32).clamp(1, MAX_PHASE_SAMPLES);
        Self {
            phase_samples: NonZeroU32::new(phase).unwrap_or(NonZeroU32::MIN),
            cycle_samples: NonZeroU32::new(8 * phase).unwrap_or(NonZeroU32::MIN),
            counter: 0,
        }
    }

    /// Samples per phase.
    pub fn phase_samples(&self) -> u32 {
        self.phase_samples.get()
    }

    /// The offsets (roll, pitch, yaw) for this sample, then advances one sample.
    pub fn next(&mut self, ln_beta_estimate: [f32; 3]) -> [f32; 3] {
        let phase = (self.counter / self.phase_samples) % 8;
        self.counter = self.counter.wrapping_add(1) % self.cycle_samples;
        let mut out = [0.0f32; 3];
        #[allow(clippy::cast_possible_truncation)] // phase < 8
        if let Some(&(axis, sign)) = PHASES.get(phase as usize)
            && let (Some(o), Some(lb), Some(cap)) = (
                out.get_mut(axis),
                ln_beta_estimate.get(axis),
                CAPS.get(axis),
            )
        {
            *o = sign * libm::expf(LN_AMPLITUDE_SCALE - lb).min(*cap);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pattern_amplitude_and_zero_mean() {
        let mut s = Shake::new(0.001, 0.075);
        assert_eq!(s.phase_samples(), 75);
        let mut sum = [0.0f32; 3];
        let mut first = [0.0f32; 3];
        for i in 0..600 {
            let o = s.next([10.0, 10.0, 5.0]);
            if i == 0 {
                first = o;
            }
            if i == 75 {
                assert!((o[0] - libm::expf(-2.9)).abs() < 1e-6, "{o:?}");
            }
            for k in 0..3 {
                sum[k] += o[k];
            }
        }
        // Yaw first, capped: exp(2.1) > 0.7.
        assert_eq!(first, [0.0, 0.0, 0.7]);
        assert!(sum.iter().all(|v| v.abs() < 1e-3), "{sum:?}");
    }

    #[test]
    fn any_phase_length_runs_without_a_zero_divisor() {
        // 2²⁹ samples a phase made the cycle 8 × 2²⁹ = 2³², i.e. 0: `%` by zero.
        for (ts, phase) in [
            (1.0, 536_870_912.0),
            (1e-30, 1.0),
            (0.001, f32::NAN),
            (0.0, 1.0),
        ] {
            let mut s = Shake::new(ts, phase);
            assert!((1..=MAX_PHASE_SAMPLES).contains(&s.phase_samples()));
            for _ in 0..20 {
                assert!(s.next([10.0; 3]).iter().all(|v| v.is_finite()));
            }
        }
        assert_eq!(
            Shake::new(1.0, 536_870_912.0).phase_samples(),
            MAX_PHASE_SAMPLES
        );
    }
}
