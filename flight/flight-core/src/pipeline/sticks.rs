//! From stick positions to setpoints: rate (deg/s) and angle (deg) per axis, with expo.

use crate::estimation::math::max;
use crate::supervisor::Sticks;

/// Stick → setpoint shaping.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StickShaping {
    /// Full-deflection rate, deg/s (roll and pitch; yaw uses half).
    pub max_rate_dps: f32,
    /// Full-deflection angle in attitude mode, deg.
    pub max_angle_deg: f32,
    /// Expo 0…1: 0 linear, 1 cubic.
    pub expo: f32,
}

impl Default for StickShaping {
    fn default() -> Self {
        Self {
            max_rate_dps: 720.0,
            max_angle_deg: 45.0,
            expo: 0.3,
        }
    }
}

impl StickShaping {
    fn shape(&self, x: f32) -> f32 {
        let x = x.clamp(-1.0, 1.0);
        (1.0 - self.expo) * x + self.expo * x * x * x
    }

    /// Yaw rate setpoint, deg/s (half the roll/pitch rate): the only rate the attitude
    /// modes use.
    pub fn yaw_rate_dps(&self, s: &Sticks) -> f32 {
        self.shape(s.yaw) * self.max_rate_dps * 0.5
    }

    /// Rate setpoints (roll, pitch, yaw), deg/s.
    pub fn rates_dps(&self, s: &Sticks) -> [f32; 3] {
        [
            self.shape(s.roll) * self.max_rate_dps,
            self.shape(s.pitch) * self.max_rate_dps,
            self.yaw_rate_dps(s),
        ]
    }

    /// Angle setpoints (roll, pitch), deg — linear, so the angle is where the stick is.
    pub fn angles_deg(&self, s: &Sticks) -> [f32; 2] {
        [
            s.roll.clamp(-1.0, 1.0) * self.max_angle_deg,
            s.pitch.clamp(-1.0, 1.0) * self.max_angle_deg,
        ]
    }

    /// Horizon blend weight: 1 (attitude) at centre, 0 (rate) at full deflection.
    pub fn horizon_weight(&self, s: &Sticks) -> f32 {
        1.0 - max(s.roll.abs(), s.pitch.abs()).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shaping_numbers() {
        let k = StickShaping::default();
        let full = Sticks {
            roll: 1.0,
            pitch: -0.5,
            yaw: 1.0,
            throttle: 0.5,
        };
        let r = k.rates_dps(&full);
        assert_eq!(r[0], 720.0);
        // 0.7·(−0.5) + 0.3·(−0.125) = −0.3875 → −279 deg/s.
        assert!((r[1] + 279.0).abs() < 1e-3, "{}", r[1]);
        assert_eq!(r[2], 360.0);
        assert_eq!(k.angles_deg(&full), [45.0, -22.5]);
        assert_eq!(k.horizon_weight(&full), 0.0);
        assert_eq!(k.horizon_weight(&Sticks::default()), 1.0);
    }
}
