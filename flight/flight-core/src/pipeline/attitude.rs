//! The attitude a loop reports ([`super::LoopOutput::attitude`]): roll and pitch in degrees,
//! worked out every step because the angle laws fly them, and the heading kept as the
//! rotation matrix's horizontal pair so that its angle — a third polynomial atan2 and a wrap,
//! ≈ 40 instructions on the M4F — is computed only when something asks for it (telemetry at
//! 25 /s, the console), not on every loop of every mode. The hold loops and the INS never
//! need the angle: they use the pair (cos ψ, sin ψ) directly.
//!
//! The angles come from a polynomial atan2 (error < 0.01°), never from libm, whose f32
//! trigonometry goes through soft double precision on the M4F.

use crate::estimation::math::{inv_sqrt, wrap_pi};

const DEG_PER_RAD: f32 = 180.0 / core::f32::consts::PI;

/// Estimated attitude: roll and pitch, and the heading (angle on demand, [`Self::yaw_deg`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attitude {
    /// Roll, deg (right side down positive), −180…180.
    pub roll_deg: f32,
    /// Pitch, deg (nose up positive), −90…90.
    pub pitch_deg: f32,
    /// (R11, R12) of the NED→body rotation: (cos ψ, sin ψ)·cos θ.
    heading: [f32; 2],
}

impl Attitude {
    /// Level, facing north.
    pub const LEVEL: Self = Self {
        roll_deg: 0.0,
        pitch_deg: 0.0,
        heading: [1.0, 0.0],
    };

    /// The Euler angles (ZYX) of a NED→body rotation matrix (`quaternion::ned_to_body`), the
    /// yaw left for later.
    pub(crate) fn from_rotation(r: &[[f32; 3]; 3]) -> Self {
        let [[r11, r12, r13], [_, _, r23], [_, _, r33]] = *r;
        let horizontal = r23 * r23 + r33 * r33;
        let cos_pitch = if horizontal > 0.0 {
            horizontal * inv_sqrt(horizontal)
        } else {
            0.0
        };
        Self {
            roll_deg: atan2(r23, r33) * DEG_PER_RAD,
            pitch_deg: atan2(-r13, cos_pitch) * DEG_PER_RAD,
            heading: [r11, r12],
        }
    }

    /// From roll, pitch and yaw in degrees (simulators and tests).
    #[must_use]
    pub fn from_deg([roll_deg, pitch_deg, yaw_deg]: [f32; 3]) -> Self {
        let (sin, cos) = crate::estimation::math::sin_cos(yaw_deg / DEG_PER_RAD);
        Self {
            roll_deg,
            pitch_deg,
            heading: [cos, sin],
        }
    }

    /// Yaw (heading), deg, −180…180 (0 when the nose points straight up or down).
    #[must_use]
    pub fn yaw_deg(&self) -> f32 {
        let [r11, r12] = self.heading;
        wrap_pi(atan2(r12, r11)) * DEG_PER_RAD
    }

    /// (roll, pitch, yaw), deg.
    #[must_use]
    pub fn deg(&self) -> [f32; 3] {
        [self.roll_deg, self.pitch_deg, self.yaw_deg()]
    }
}

/// atan2 by octant reduction and a degree-9 odd minimax polynomial on [−1, 1].
pub(crate) fn atan2(y: f32, x: f32) -> f32 {
    use core::f32::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    if ax == 0.0 && ay == 0.0 {
        return 0.0;
    }
    let swap = ay > ax;
    let z = if swap { ax / ay } else { ay / ax };
    let z2 = z * z;
    let mut a = z
        * (0.999_866
            + z2 * (-0.330_299_5 + z2 * (0.180_141 + z2 * (-0.085_133 + z2 * 0.020_835_1))));
    if swap {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    if y < 0.0 { -a } else { a }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimation::quaternion::{from_euler, ned_to_body};

    #[test]
    fn atan2_matches_libm() {
        let mut worst = 0.0f32;
        for i in -50..=50 {
            for j in -50..=50 {
                let (y, x) = (i as f32 * 0.37, j as f32 * 0.41);
                worst = worst.max((atan2(y, x) - libm::atan2f(y, x)).abs());
            }
        }
        assert!(worst < 2e-5, "{worst}");
    }

    #[test]
    fn the_yaw_asked_for_later_is_the_attitudes() {
        for (roll, pitch, yaw) in [
            (0.0, 0.0, 0.0),
            (20.0, -10.0, 120.0),
            (-35.0, 40.0, -170.0),
            (170.0, -5.0, 179.9),
            (5.0, 80.0, -90.0),
        ] {
            let q = from_euler(
                f32::to_radians(roll),
                f32::to_radians(pitch),
                f32::to_radians(yaw),
            );
            let a = Attitude::from_rotation(&ned_to_body(q));
            let [r, p, y] = a.deg();
            let close = |a: f32, b: f32| {
                let d = (a - b).rem_euclid(360.0);
                d.min(360.0 - d) < 0.01
            };
            assert!(
                close(r, roll) && close(p, pitch) && close(y, yaw),
                "{:?} for {roll} {pitch} {yaw}",
                a.deg()
            );
        }
    }

    #[test]
    fn from_deg_keeps_roll_and_pitch_and_the_yaw_within_the_atan2_error() {
        let a = Attitude::from_deg([12.5, -3.0, 123.455]);
        assert_eq!((a.roll_deg, a.pitch_deg), (12.5, -3.0));
        assert!((a.yaw_deg() - 123.455).abs() < 0.005, "{}", a.yaw_deg());
        assert_eq!(Attitude::LEVEL.deg(), [0.0; 3]);
    }
}
