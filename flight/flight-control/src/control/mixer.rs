//! Motor mixer: (throttle, roll, pitch, yaw) → per-motor commands in [0, 1], for quad X,
//! quad + and hexacopter X, with desaturation and optional thrust linearisation.
//!
//! Desaturation keeps attitude authority at both ends of the throttle range ("air mode"):
//! the attitude part of the mix is scaled down only if its span exceeds the whole motor
//! range; otherwise throttle is shifted so every motor fits. Attitude wins over throttle
//! because losing attitude control at zero throttle is what flips a quad.

use crate::estimation::math::{max, min};

/// One motor's share of roll, pitch and yaw.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MotorFactors {
    /// Roll factor (positive: this motor's thrust rolls right).
    pub roll: f32,
    /// Pitch factor (positive: nose up).
    pub pitch: f32,
    /// Yaw factor (positive: nose right; sign = the prop's reaction direction).
    pub yaw: f32,
}

const fn m(roll: f32, pitch: f32, yaw: f32) -> MotorFactors {
    MotorFactors { roll, pitch, yaw }
}

/// Thrust curve correction for the output stage.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ThrustCurve {
    /// Commands pass through (ESC/brushless with its own linearisation).
    Linear,
    /// Thrust ≈ (1 − k)·c + k·c² (brushed motors: k near 1); the mixer inverts it so that the
    /// commanded thrust share is what the motor delivers.
    Quadratic {
        /// Quadratic share k in [0, 1].
        k: f32,
    },
}

impl ThrustCurve {
    /// Command that yields thrust fraction `t` in [0, 1].
    pub fn command_for(self, t: f32) -> f32 {
        match self {
            ThrustCurve::Linear => t,
            ThrustCurve::Quadratic { k } if k > 1e-3 => {
                // Root of k·c² + (1 − k)·c − t = 0 in the form without cancellation.
                let a = 1.0 - k;
                2.0 * t / (a + libm::sqrtf(a * a + 4.0 * k * t))
            }
            ThrustCurve::Quadratic { .. } => t,
        }
    }
}

/// A mixer for N motors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mixer<const N: usize> {
    factors: [MotorFactors; N],
    curve: ThrustCurve,
    /// The factors are [`QUAD_X`] (the factory frame): mixed in straight-line code.
    quad_x: bool,
}

/// Quad X, motors 1–4: front-right (CCW), rear-right (CW), rear-left (CCW), front-left (CW).
pub const QUAD_X: [MotorFactors; 4] = [
    m(-0.5, 0.5, -0.5),
    m(-0.5, -0.5, 0.5),
    m(0.5, -0.5, -0.5),
    m(0.5, 0.5, 0.5),
];
/// Quad +, motors 1–4: front (CW), right (CCW), rear (CW), left (CCW).
pub const QUAD_PLUS: [MotorFactors; 4] = [
    m(0.0, 1.0, 0.5),
    m(-1.0, 0.0, -0.5),
    m(0.0, -1.0, 0.5),
    m(1.0, 0.0, -0.5),
];
/// Hexacopter X, clockwise from front-right at 30°; alternating prop directions.
pub const HEX_X: [MotorFactors; 6] = [
    m(-0.5, 0.866, 0.5),
    m(-1.0, 0.0, -0.5),
    m(-0.5, -0.866, 0.5),
    m(0.5, -0.866, -0.5),
    m(1.0, 0.0, 0.5),
    m(0.5, 0.866, -0.5),
];

/// The factors are exactly [`QUAD_X`]'s (const: decided when the mixer is built).
const fn is_quad_x(factors: &[MotorFactors]) -> bool {
    let (mut f, mut q): (&[MotorFactors], &[MotorFactors]) = (factors, &QUAD_X);
    if f.len() != q.len() {
        return false;
    }
    while let ([a, f_rest @ ..], [b, q_rest @ ..]) = (f, q) {
        if a.roll != b.roll || a.pitch != b.pitch || a.yaw != b.yaw {
            return false;
        }
        (f, q) = (f_rest, q_rest);
    }
    true
}

impl<const N: usize> Mixer<N> {
    /// A mixer with the given geometry and thrust curve.
    pub const fn new(factors: [MotorFactors; N], curve: ThrustCurve) -> Self {
        Self {
            factors,
            curve,
            quad_x: is_quad_x(&factors),
        }
    }

    /// Each motor's attitude part and the parts' lowest and highest value (≤ 0 ≤).
    #[inline(always)]
    fn parts(&self, [roll, pitch, yaw]: [f32; 3]) -> ([f32; N], f32, f32) {
        if self.quad_x {
            // QUAD_X's ±0.5 factors, the same roundings as the general sums (halving is
            // exact): motors −a+b−c, −a−b+c, a−b−c, a+b+c. The extremes pair up as −c ± |b−a|
            // and c ± |a+b|; the parts sum to 0, so lo ≤ 0 ≤ hi as in the general fold.
            let (a, b, c) = (0.5 * roll, 0.5 * pitch, 0.5 * yaw);
            let (u, v) = (b - a, a + b);
            let q = [u - c, c - v, -(u + c), v + c];
            // Plain compares: a NaN demand makes both NaN, which the desaturation below
            // ignores exactly as the general fold's NaN parts.
            let (au, av) = (u.abs(), v.abs());
            let (lo1, lo2, hi1, hi2) = (-c - au, c - av, au - c, c + av);
            let lo = if lo2 < lo1 { lo2 } else { lo1 };
            let hi = if hi2 > hi1 { hi2 } else { hi1 };
            let parts = core::array::from_fn(|i| q.get(i).copied().unwrap_or(0.0));
            return (parts, lo, hi);
        }
        let parts = self
            .factors
            .map(|f| f.roll * roll + f.pitch * pitch + f.yaw * yaw);
        let (lo, hi) = parts.iter().fold((0.0f32, 0.0f32), |(lo, hi), &p| {
            // The accumulators start at 0 and never take a NaN (a NaN part fails both
            // compares), so plain compares give exactly `lo.min(p)` and `hi.max(p)`.
            (if p < lo { p } else { lo }, if p > hi { p } else { hi })
        });
        (parts, lo, hi)
    }

    /// Mixes throttle in [0, 1] and (roll, pitch, yaw) in ±1 into motor commands in [0, 1].
    pub fn mix(&self, throttle: f32, attitude: [f32; 3]) -> [f32; N] {
        self.mix_with_applied(throttle, attitude).0
    }

    /// [`Self::mix`], also returning the (roll, pitch, yaw) the motors will realise: the
    /// request times the desaturation scale. Controllers and the identification EKF that
    /// predict with their own output must be told this, not the request (see
    /// `sysid::ekf::SystemIdentifier::record_output`).
    pub fn mix_with_applied(&self, throttle: f32, attitude: [f32; 3]) -> ([f32; N], [f32; 3]) {
        let (parts, lo, hi) = self.parts(attitude);
        let span = hi - lo;
        // Scale the attitude part only when it alone cannot fit into [0, 1].
        let scale = if span > 1.0 { 1.0 / span } else { 1.0 };
        let (lo, hi) = (lo * scale, hi * scale);
        // Shift throttle so that min ≥ 0 and max ≤ 1 (both hold after scaling).
        // min/max, not clamp: after scaling −lo and 1 − hi can cross by one ulp, and clamp
        // panics on crossed bounds.
        let t = max(min(throttle.clamp(0.0, 1.0), 1.0 - hi), -lo);
        let thrust = parts.map(|p| t + p * scale);
        // Rounding is monotonic, so the lowest and highest motors are exactly t + lo and
        // t + hi (or within them): when those fit, as they do unless rounding pushed one
        // past an end, every motor does and the per-motor clamp is skipped.
        let thrust = if t + lo >= 0.0 && t + hi <= 1.0 {
            thrust
        } else {
            thrust.map(|x| x.clamp(0.0, 1.0))
        };
        // The curve is fixed per mixer: decided once, not per motor.
        let motors = match self.curve {
            ThrustCurve::Linear => thrust,
            curve => thrust.map(|x| curve.command_for(x)),
        };
        (motors, attitude.map(|a| a * scale))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quad_x_mixes_and_keeps_authority() {
        let mx = Mixer::new(QUAD_X, ThrustCurve::Linear);
        assert_eq!(mx.mix(0.5, [0.0; 3]), [0.5; 4]);
        let r = mx.mix(0.5, [0.2, 0.0, 0.0]);
        assert_eq!(r, [0.4, 0.4, 0.6, 0.6]);
        // Zero throttle: roll still produces a difference (throttle is raised to make room).
        let low = mx.mix(0.0, [0.2, 0.0, 0.0]);
        assert!(
            (low[2] - low[0] - 0.2).abs() < 1e-6 && low[0].abs() < 1e-6,
            "{low:?}"
        );
        // Full throttle: shifted down, difference kept.
        let high = mx.mix(1.0, [0.2, 0.0, 0.0]);
        assert!((high[2] - high[0] - 0.2).abs() < 1e-6 && (high[2] - 1.0).abs() < 1e-6);
        // Too much demand: scaled so the span is exactly 1 and ratios are kept.
        // Crossed bounds by rounding (span exactly 1 after scaling) must not panic.
        let edge = mx.mix(0.9, [0.5037707, -0.5037707, 0.3]);
        assert!(edge.iter().all(|m| (0.0..=1.0).contains(m)), "{edge:?}");
        let sat = mx.mix(0.5, [1.0, 1.0, 0.0]);
        assert!(
            (sat[3] - 1.0).abs() < 1e-6 && sat[1].abs() < 1e-6,
            "{sat:?}"
        );
        // What is realised: the request within the range, halved when the span is 2.
        assert_eq!(
            mx.mix_with_applied(0.5, [0.2, 0.1, -0.3]).1,
            [0.2, 0.1, -0.3]
        );
        let (motors, applied) = mx.mix_with_applied(0.5, [1.0, 1.0, 0.0]);
        assert_eq!(motors, sat);
        assert_eq!(applied, [0.5, 0.5, 0.0]);
    }

    #[test]
    fn the_straight_line_quad_x_mix_is_the_general_one_bit_for_bit() {
        let fast = Mixer::new(QUAD_X, ThrustCurve::Linear);
        assert!(fast.quad_x && !Mixer::new(QUAD_PLUS, ThrustCurve::Linear).quad_x);
        let general = Mixer {
            quad_x: false,
            ..fast
        };
        let values = [
            f32::NAN,
            -1.7,
            -1.0,
            -0.5037707,
            -0.3,
            -1e-7,
            -0.0,
            0.0,
            0.013,
            0.2,
            0.5037707,
            0.77,
            1.0,
        ];
        let same = |a: &[f32], b: &[f32]| {
            a.iter()
                .zip(b)
                .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
        };
        for throttle in [0.0, 0.05, 0.5, 0.93, 1.0] {
            for r in values {
                for p in values {
                    for y in values {
                        let (m1, a1) = fast.mix_with_applied(throttle, [r, p, y]);
                        let (m2, a2) = general.mix_with_applied(throttle, [r, p, y]);
                        assert!(
                            same(&m1, &m2) && same(&a1, &a2),
                            "{throttle} {r} {p} {y}: {m1:?} {a1:?} vs {m2:?} {a2:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn geometries_sum_to_zero_and_curve_inverts() {
        for f in [&QUAD_X[..], &QUAD_PLUS[..], &HEX_X[..]] {
            let (r, p, y) = f.iter().fold((0.0, 0.0, 0.0), |a, m| {
                (a.0 + m.roll, a.1 + m.pitch, a.2 + m.yaw)
            });
            assert!(r.abs() < 1e-3 && p.abs() < 1e-3 && y.abs() < 1e-3);
        }
        let hex = Mixer::new(HEX_X, ThrustCurve::Linear).mix(0.5, [0.0, 0.0, 0.1]);
        assert!((hex[0] - 0.55).abs() < 1e-6 && (hex[1] - 0.45).abs() < 1e-6);
        let c = ThrustCurve::Quadratic { k: 0.8 };
        for t in [0.0f32, 0.1, 0.5, 1.0] {
            let cmd = c.command_for(t);
            assert!(((0.2 * cmd + 0.8 * cmd * cmd) - t).abs() < 1e-6);
        }
    }
}
