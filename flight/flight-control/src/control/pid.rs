//! PID rate and attitude controllers: the default controller and the LQG's baseline.
//!
//! Parallel form C = kp + ki/s + kd·s/(τ_d·s + 1) (the form the analytic autotune of
//! `control/LQG.md` §6 designs for), discretised with backward Euler so the derivative filter is
//! stable for any τ_d. Setpoint weighting: P acts on b·sp − y and D on c·sp − y (c = 0 avoids the
//! derivative kick on stick steps). Anti-windup: the integrator freezes while the output is
//! saturated in the direction the error would push it, and is clamped. Every limit goes
//! through [`clamp_abs`]: the limits come from settings, and `f32::clamp` panics on crossed
//! or NaN bounds.

use crate::estimation::math::clamp_abs;

/// Gains and shaping of one PID.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PidGains {
    /// Proportional gain (output units per input unit).
    pub kp: f32,
    /// Integral gain (per second).
    pub ki: f32,
    /// Derivative gain (seconds).
    pub kd: f32,
    /// Derivative filter time constant τ_d, s (cutoff 1/(2π·τ_d)).
    pub derivative_tau_s: f32,
    /// Setpoint weight b of the P term.
    pub setpoint_weight_p: f32,
    /// Setpoint weight c of the D term.
    pub setpoint_weight_d: f32,
    /// |integral term| limit (output units).
    pub integral_limit: f32,
    /// |output| limit.
    pub output_limit: f32,
}

impl PidGains {
    /// Gains with b = 1, c = 0, integral limit 0.3, output limit 1.
    pub fn new(kp: f32, ki: f32, kd: f32, derivative_tau_s: f32) -> Self {
        Self {
            kp,
            ki,
            kd,
            derivative_tau_s,
            setpoint_weight_p: 1.0,
            setpoint_weight_d: 0.0,
            integral_limit: 0.3,
            output_limit: 1.0,
        }
    }
}

/// One PID loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pid {
    gains: PidGains,
    ts_s: f32,
    integral: f32,
    derivative: f32,
    last_d_input: Option<f32>,
}

impl Pid {
    /// A PID running every `ts_s` seconds.
    pub fn new(gains: PidGains, ts_s: f32) -> Self {
        Self {
            gains,
            ts_s,
            integral: 0.0,
            derivative: 0.0,
            last_d_input: None,
        }
    }

    /// Clears the integrator and derivative history.
    pub fn reset(&mut self) {
        self.integral = 0.0;
        self.derivative = 0.0;
        self.last_d_input = None;
    }

    /// The integral term (for tests and telemetry).
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// One step; returns the clamped output.
    pub fn update(&mut self, setpoint: f32, measurement: f32) -> f32 {
        let g = &self.gains;
        let error = setpoint - measurement;
        let p = g.kp * (g.setpoint_weight_p * setpoint - measurement);
        let d_input = g.setpoint_weight_d * setpoint - measurement;
        // First sample: no history, no derivative kick.
        let delta = self.last_d_input.map_or(0.0, |last| d_input - last);
        self.last_d_input = Some(d_input);
        // (τ_d + Ts)·d_k = τ_d·d_{k−1} + kd·Δx_k (backward Euler of kd·s/(τ_d·s + 1)).
        self.derivative = (g.derivative_tau_s * self.derivative + g.kd * delta)
            / (g.derivative_tau_s + self.ts_s);
        let unsaturated = p + self.integral + self.derivative;
        let limit = g.output_limit.abs();
        let pushing_further =
            (unsaturated >= limit && error > 0.0) || (unsaturated <= -limit && error < 0.0);
        if !pushing_further {
            self.integral = clamp_abs(self.integral + g.ki * self.ts_s * error, g.integral_limit);
        }
        let out = p + self.integral + self.derivative;
        if out.is_nan() {
            0.0
        } else {
            clamp_abs(out, g.output_limit)
        }
    }
}

/// Attitude PID: an outer angle loop (P + optional I) producing a rate setpoint for an
/// inner rate [`Pid`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttitudePid {
    /// Outer proportional gain, (deg/s) per deg.
    outer_kp: f32,
    /// Outer integral gain, (deg/s) per deg·s.
    outer_ki: f32,
    max_rate_dps: f32,
    ts_s: f32,
    outer_integral: f32,
    rate: Pid,
}

impl AttitudePid {
    /// Outer gains, rate-setpoint limit and the inner rate PID.
    pub fn new(outer_kp: f32, outer_ki: f32, max_rate_dps: f32, rate: Pid, ts_s: f32) -> Self {
        Self {
            outer_kp,
            outer_ki,
            max_rate_dps,
            ts_s,
            outer_integral: 0.0,
            rate,
        }
    }

    /// Clears both loops.
    pub fn reset(&mut self) {
        self.outer_integral = 0.0;
        self.rate.reset();
    }

    /// The rate setpoint the outer loop asks for, deg/s.
    pub fn rate_setpoint(&self, angle_error_deg: f32) -> f32 {
        clamp_abs(
            self.outer_kp * angle_error_deg + self.outer_integral,
            self.max_rate_dps,
        )
    }

    /// One step from the angle error (deg) and the gyro (deg/s); returns the output.
    pub fn update(&mut self, angle_error_deg: f32, gyro_dps: f32) -> f32 {
        let limit = 0.25 * self.max_rate_dps;
        self.outer_integral = clamp_abs(
            self.outer_integral + self.outer_ki * self.ts_s * angle_error_deg,
            limit,
        );
        let sp = self.rate_setpoint(angle_error_deg);
        self.rate.update(sp, gyro_dps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverted_or_nan_limits_never_panic() {
        // A negative limit is clamp's crossed bounds (min > max), a NaN one its NaN bound:
        // both panicked in `f32::clamp`. The magnitude counts; NaN leaves the value.
        let mut gains = PidGains::new(2.0, 50.0, 0.0, 0.01);
        gains.integral_limit = -0.1;
        gains.output_limit = -0.5;
        let mut pid = Pid::new(gains, 0.001);
        for _ in 0..400 {
            pid.update(0.01, 0.0);
        }
        assert_eq!(pid.integral(), 0.1);
        assert!((pid.update(0.01, 0.0) - 0.12).abs() < 1e-6);
        assert_eq!(pid.update(10.0, 0.0), 0.5);
        gains.output_limit = f32::NAN;
        let mut pid = Pid::new(gains, 0.001);
        assert_eq!(pid.update(0.25, 0.0), 0.5 + 50.0 * 0.001 * 0.25);
        let mut att = AttitudePid::new(
            1.0,
            1.0,
            -100.0,
            Pid::new(PidGains::new(0.01, 0.0, 0.0, 0.01), 0.001),
            0.001,
        );
        assert_eq!(att.rate_setpoint(1_000.0), 100.0);
        assert!(att.update(1_000.0, 0.0).is_finite());
    }

    #[test]
    fn pid_terms_and_anti_windup() {
        let mut pid = Pid::new(PidGains::new(0.01, 0.5, 0.0, 0.005), 0.001);
        // Pure P on first step with b = 1: 0.01·10 plus one integral step 0.5·0.001·10.
        let u = pid.update(10.0, 0.0);
        assert!((u - (0.1 + 0.005)).abs() < 1e-6, "{u}");
        // Saturate for a long time: the integral must stop at its limit, not run away.
        for _ in 0..10_000 {
            pid.update(1000.0, 0.0);
        }
        assert!(pid.integral() <= 0.3 + 1e-6);
        assert_eq!(pid.update(1000.0, 0.0), 1.0);
        // Derivative on measurement only (c = 0): a setpoint step produces no D kick.
        let mut d = Pid::new(PidGains::new(0.0, 0.0, 0.001, 0.0), 0.001);
        d.update(0.0, 0.0);
        assert_eq!(d.update(100.0, 0.0), 0.0);
        // A measurement ramp of 1 deg/s per step gives −kd·1/Ts = −1 (unfiltered).
        assert!((d.update(100.0, 1.0) + 1.0).abs() < 1e-6);
    }

    #[test]
    fn attitude_pid_limits_rate_setpoint() {
        let inner = Pid::new(PidGains::new(0.002, 0.0, 0.0, 0.005), 0.001);
        let att = AttitudePid::new(7.3, 0.0, 500.0, inner, 0.001);
        assert_eq!(att.rate_setpoint(10.0), 73.0);
        assert_eq!(att.rate_setpoint(1000.0), 500.0);
    }
}
