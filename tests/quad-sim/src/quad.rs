//! A 6-DoF quadrotor (any motor count) for closed-loop tests and, later, the flight SITL and
//! the link simulator: rigid body with full inertia coupling, first-order motor lag, thrust
//! curve, prop-drag yaw torque, optional lag-free yaw torque, whole-sample output latency,
//! and a gyro/accelerometer with seeded noise and bias. No globals; all randomness comes
//! from the seed.
//!
//! Frames: NED world, FRD body; the attitude quaternion rotates body → world. A motor at
//! body position (x, y) pushing −z with thrust T gives torque (−y·T, x·T, 0).

use flight_core::control::mixer::MotorFactors;
use sim_rng::{GOLDEN_GAMMA, SplitMix64};
use std::collections::VecDeque;
use std::f64::consts::PI;

/// Standard gravity, m/s².
pub const GRAVITY_MPS2: f64 = 9.806_65;
const DEG: f64 = 180.0 / PI;

/// Where a motor sits and which way its reaction torque turns the frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorGeometry {
    /// Body position (forward, right), m.
    pub position_m: [f64; 2],
    /// +1: drag torque yaws the nose right when this motor speeds up; −1: left.
    pub yaw_sign: f64,
}

/// Physical and sensor parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadParams {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Principal moments of inertia (roll, pitch, yaw), kg·m².
    pub inertia_kg_m2: [f64; 3],
    /// Motor layout; commands are indexed in this order.
    pub motors: Vec<MotorGeometry>,
    /// Thrust of one motor at full command, N.
    pub max_thrust_n: f64,
    /// Motor/prop time constant τ, s.
    pub motor_tau_s: f64,
    /// Thrust curve T = Tmax·((1 − k)·m + k·m²) of the lagged motor state m (0 = linear).
    pub thrust_curve_k: f64,
    /// Prop drag yaw torque per newton of thrust, m.
    pub yaw_drag_m: f64,
    /// Lag-free yaw torque per unit of (command − motor state), N·m (prop acceleration; β2).
    pub yaw_direct_nm: f64,
    /// Linear air drag, N per m/s of airspeed.
    pub linear_drag_n_per_mps: f64,
    /// Steady wind, NED m/s (the air's velocity: drag acts on velocity − wind).
    pub wind_ned_mps: [f64; 3],
    /// Whole loop periods between a command and the motors seeing it.
    pub latency_samples: usize,
    /// Integration sub-steps per `step`.
    pub substeps: u32,
    /// Gyro white noise σ, deg/s.
    pub gyro_noise_dps: f64,
    /// Gyro bias, deg/s.
    pub gyro_bias_dps: [f64; 3],
    /// Accelerometer white noise σ, m/s².
    pub accel_noise_mps2: f64,
    /// Negate every sensor noise sample of the seed (the antithetic twin run, for expected
    /// responses; see `closed_loop::ensemble`).
    pub antithetic_noise: bool,
}

impl QuadParams {
    /// A quad X matching `flight_core::control::mixer::QUAD_X` (motor order and yaw signs),
    /// sized so that roll/pitch have authority exp(`ln_beta`) and yaw exp(`ln_beta_yaw`) in
    /// (deg/s²) per unit of mixer input, with motor time constant `tau_s`. 250-class: 0.5 kg,
    /// 0.125 m diagonal half-arm, 8 N motors.
    pub fn quad_x(ln_beta: f64, ln_beta_yaw: f64, tau_s: f64, factors: &[MotorFactors; 4]) -> Self {
        let arm = 0.125;
        let max_thrust_n = 8.0;
        let yaw_drag_m = 0.016;
        let s = arm / 2f64.sqrt();
        let motors = factors
            .iter()
            .map(|f| MotorGeometry {
                position_m: [
                    s * f64::from(f.pitch.signum()),
                    -s * f64::from(f.roll.signum()),
                ],
                yaw_sign: f64::from(f.yaw.signum()),
            })
            .collect();
        // β = DEG·(Σ|factor·lever|)·Tmax / I  →  I = DEG·lever_sum·Tmax / β.
        let i_rp = DEG * 4.0 * 0.5 * s * max_thrust_n / ln_beta.exp();
        let i_y = DEG * 4.0 * 0.5 * yaw_drag_m * max_thrust_n / ln_beta_yaw.exp();
        Self {
            mass_kg: 0.5,
            inertia_kg_m2: [i_rp, i_rp, i_y],
            motors,
            max_thrust_n,
            motor_tau_s: tau_s,
            thrust_curve_k: 0.0,
            yaw_drag_m,
            yaw_direct_nm: 0.0,
            linear_drag_n_per_mps: 0.1,
            wind_ned_mps: [0.0; 3],
            latency_samples: 1,
            substeps: 8,
            gyro_noise_dps: 3.0,
            gyro_bias_dps: [0.0; 3],
            accel_noise_mps2: 0.05,
            antithetic_noise: false,
        }
    }

    /// Throttle (thrust fraction) that hovers, for a linear thrust curve.
    pub fn hover_throttle(&self) -> f64 {
        #[allow(clippy::cast_precision_loss)]
        let n = self.motors.len() as f64;
        self.mass_kg * GRAVITY_MPS2 / (n * self.max_thrust_n)
    }

    /// Small-signal ln β (roll, pitch, yaw) for a mixer with these `factors`, linear curve.
    pub fn ln_beta(&self, factors: &[MotorFactors]) -> [f64; 3] {
        let mut torque = [0.0f64; 3];
        for (m, f) in self.motors.iter().zip(factors) {
            let [x, y] = m.position_m;
            torque[0] += -y * f64::from(f.roll) * self.max_thrust_n;
            torque[1] += x * f64::from(f.pitch) * self.max_thrust_n;
            torque[2] += m.yaw_sign * self.yaw_drag_m * f64::from(f.yaw) * self.max_thrust_n;
        }
        let [tx, ty, tz] = torque;
        let [ix, iy, iz] = self.inertia_kg_m2;
        [
            (DEG * tx / ix).ln(),
            (DEG * ty / iy).ln(),
            (DEG * tz / iz).ln(),
        ]
    }
}

/// Full rigid-body and motor state.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadState {
    /// Position, NED, m.
    pub position_m: [f64; 3],
    /// Velocity, NED, m/s.
    pub velocity_mps: [f64; 3],
    /// Attitude quaternion (w, x, y, z), body → NED.
    pub attitude: [f64; 4],
    /// Body rates (roll, pitch, yaw), rad/s.
    pub rate_rad_s: [f64; 3],
    /// Lagged motor states m ∈ [0, 1].
    pub motor: Vec<f64>,
}

/// What the flight controller's sensors report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensors {
    /// Gyro, deg/s (roll, pitch, yaw).
    pub gyro_dps: [f32; 3],
    /// Accelerometer specific force, body, m/s².
    pub accel_mps2: [f32; 3],
}

/// Ground truth after a step.
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    /// The state.
    pub state: QuadState,
    /// Euler angles (roll, pitch, yaw), deg, ZYX.
    pub euler_deg: [f64; 3],
    /// Body rates, deg/s.
    pub rate_dps: [f64; 3],
}

/// The simulated quadrotor.
#[derive(Debug, Clone)]
pub struct Quad {
    params: QuadParams,
    state: QuadState,
    queue: VecDeque<Vec<f64>>,
    rng: SplitMix64,
}

fn quat_rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let [a, b, c] = v;
    [
        (1.0 - 2.0 * (y * y + z * z)) * a + 2.0 * (x * y - w * z) * b + 2.0 * (x * z + w * y) * c,
        2.0 * (x * y + w * z) * a + (1.0 - 2.0 * (x * x + z * z)) * b + 2.0 * (y * z - w * x) * c,
        2.0 * (x * z - w * y) * a + 2.0 * (y * z + w * x) * b + (1.0 - 2.0 * (x * x + y * y)) * c,
    ]
}

fn quat_conj(q: [f64; 4]) -> [f64; 4] {
    let [w, x, y, z] = q;
    [w, -x, -y, -z]
}

/// ZYX Euler angles (roll, pitch, yaw) in degrees of a body → NED quaternion.
pub fn euler_deg(q: [f64; 4]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    [roll * DEG, pitch * DEG, yaw * DEG]
}

impl Quad {
    /// A quad hovering at 10 m, level, motors at hover.
    pub fn new(params: QuadParams, seed: u64) -> Self {
        let hover = params.hover_throttle();
        let n = params.motors.len();
        let state = QuadState {
            position_m: [0.0, 0.0, -10.0],
            velocity_mps: [0.0; 3],
            attitude: [1.0, 0.0, 0.0, 0.0],
            rate_rad_s: [0.0; 3],
            motor: vec![hover; n],
        };
        let queue = std::iter::repeat_n(vec![hover; n], params.latency_samples).collect();
        Self {
            params,
            state,
            queue,
            rng: SplitMix64::new(seed ^ GOLDEN_GAMMA),
        }
    }

    /// Parameters.
    pub fn params(&self) -> &QuadParams {
        &self.params
    }

    /// The current state.
    pub fn state(&self) -> &QuadState {
        &self.state
    }

    /// Overwrites the state (scenario setup).
    pub fn set_state(&mut self, state: QuadState) {
        self.state = state;
    }

    /// Samples the sensors at the current state.
    pub fn sensors(&mut self) -> Sensors {
        let p = &self.params;
        let sign = if p.antithetic_noise { -1.0 } else { 1.0 };
        let mut gyro = [0.0f32; 3];
        for ((g, rate), bias) in gyro
            .iter_mut()
            .zip(self.state.rate_rad_s)
            .zip(p.gyro_bias_dps)
        {
            #[allow(clippy::cast_possible_truncation)]
            let v = (rate * DEG + bias + sign * p.gyro_noise_dps * self.rng.gaussian()) as f32;
            *g = v;
        }
        let thrust: f64 = self.state.motor.iter().map(|m| self.thrust(*m)).sum();
        let [vn, ve, vd] = self.state.velocity_mps;
        let [wn, we, wd] = p.wind_ned_mps;
        let drag_world =
            [vn - wn, ve - we, vd - wd].map(|v| -p.linear_drag_n_per_mps * v / p.mass_kg);
        let drag_body = quat_rotate(quat_conj(self.state.attitude), drag_world);
        let f = [
            drag_body[0],
            drag_body[1],
            drag_body[2] - thrust / p.mass_kg,
        ];
        let accel = f.map(|a| {
            #[allow(clippy::cast_possible_truncation)]
            let v = (a + sign * p.accel_noise_mps2 * self.rng.gaussian()) as f32;
            v
        });
        Sensors {
            gyro_dps: gyro,
            accel_mps2: accel,
        }
    }

    fn thrust(&self, m: f64) -> f64 {
        let k = self.params.thrust_curve_k;
        self.params.max_thrust_n * ((1.0 - k) * m + k * m * m)
    }

    /// Applies motor commands (each clamped to [0, 1], missing ones = 0), advances `dt_s`,
    /// and returns the sensors sampled at the end and the truth.
    pub fn step(&mut self, dt_s: f64, motor_commands: &[f32]) -> (Sensors, Truth) {
        let n = self.params.motors.len();
        let cmd: Vec<f64> = (0..n)
            .map(|i| {
                motor_commands
                    .get(i)
                    .map_or(0.0, |c| f64::from(*c).clamp(0.0, 1.0))
            })
            .collect();
        self.queue.push_back(cmd);
        let applied = self.queue.pop_front().unwrap_or_else(|| vec![0.0; n]);
        let sub = f64::from(self.params.substeps.max(1));
        for _ in 0..self.params.substeps.max(1) {
            self.integrate(dt_s / sub, &applied);
        }
        let sensors = self.sensors();
        let truth = Truth {
            euler_deg: euler_deg(self.state.attitude),
            rate_dps: self.state.rate_rad_s.map(|r| r * DEG),
            state: self.state.clone(),
        };
        (sensors, truth)
    }

    fn integrate(&mut self, h: f64, cmd: &[f64]) {
        let p = self.params.clone();
        let decay = (-h / p.motor_tau_s).exp();
        let mut torque = [0.0f64; 3];
        let mut total = 0.0;
        for ((geo, m), c) in p.motors.iter().zip(self.state.motor.iter_mut()).zip(cmd) {
            // Lag-free part from the prop acceleration (c − m), then the exact first-order lag.
            torque[2] += geo.yaw_sign * p.yaw_direct_nm * (c - *m);
            *m = c + (*m - c) * decay;
            let k = p.thrust_curve_k;
            let t = p.max_thrust_n * ((1.0 - k) * *m + k * *m * *m);
            total += t;
            let [x, y] = geo.position_m;
            torque[0] += -y * t;
            torque[1] += x * t;
            torque[2] += geo.yaw_sign * p.yaw_drag_m * t;
        }
        let s = &mut self.state;
        let [w0, w1, w2] = s.rate_rad_s;
        let i = p.inertia_kg_m2;
        let [i0, i1, i2] = i;
        let (iw0, iw1, iw2) = (i0 * w0, i1 * w1, i2 * w2);
        // ω̇ = I⁻¹(τ − ω × Iω)
        let gyroscopic = [
            w1 * iw2 - w2 * iw1,
            w2 * iw0 - w0 * iw2,
            w0 * iw1 - w1 * iw0,
        ];
        for (((w, t), g), inertia) in s.rate_rad_s.iter_mut().zip(torque).zip(gyroscopic).zip(i) {
            *w += h * (t - g) / inertia;
        }
        let [qw, qx, qy, qz] = s.attitude;
        let [wx, wy, wz] = s.rate_rad_s;
        let dq = [
            0.5 * (-qx * wx - qy * wy - qz * wz),
            0.5 * (qw * wx + qy * wz - qz * wy),
            0.5 * (qw * wy - qx * wz + qz * wx),
            0.5 * (qw * wz + qx * wy - qy * wx),
        ];
        let [d0, d1, d2, d3] = dq;
        let mut q = [qw + h * d0, qx + h * d1, qy + h * d2, qz + h * d3];
        let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        q = q.map(|v| v / norm);
        s.attitude = q;
        let thrust_world = quat_rotate(q, [0.0, 0.0, -total]);
        let gravity = [0.0, 0.0, GRAVITY_MPS2];
        for ((((v, pos), f), g), w) in s
            .velocity_mps
            .iter_mut()
            .zip(s.position_m.iter_mut())
            .zip(thrust_world)
            .zip(gravity)
            .zip(p.wind_ned_mps)
        {
            let a = f / p.mass_kg + g - p.linear_drag_n_per_mps * (*v - w) / p.mass_kg;
            *v += h * a;
            *pos += h * *v;
        }
        // Ground at z = 0 (NED): no sinking through it.
        if s.position_m[2] > 0.0 {
            s.position_m[2] = 0.0;
            s.velocity_mps = [0.0; 3];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flight_core::control::mixer::{Mixer, QUAD_X, ThrustCurve};

    fn altitude_change(k: f64, curve: ThrustCurve) -> f64 {
        let mut p = QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X);
        p.thrust_curve_k = k;
        p.gyro_noise_dps = 0.0;
        // No latency queue: it starts filled with the linear hover command.
        p.latency_samples = 0;
        let hover = p.hover_throttle() as f32;
        let mut q = Quad::new(p, 1);
        // Start with the motors where the output stage will hold them.
        let mut s = q.state().clone();
        s.motor = vec![f64::from(curve.command_for(hover)); 4];
        q.set_state(s);
        let mixer = Mixer::new(QUAD_X, curve);
        for _ in 0..1000 {
            q.step(0.001, &mixer.mix(hover, [0.0; 3]));
        }
        q.state().position_m[2] + 10.0
    }

    #[test]
    fn hovers_and_thrust_linearisation_matters_for_brushed_motors() {
        // Linear motors: hover throttle holds altitude within 1 mm over 1 s.
        assert!(altitude_change(0.0, ThrustCurve::Linear).abs() < 1e-3);
        // Brushed (T ∝ 0.2·m + 0.8·m²): without linearisation the hover throttle sinks
        // metres per second; with the mixer's inversion it holds.
        assert!(altitude_change(0.8, ThrustCurve::Linear) > 1.0);
        let lin = altitude_change(0.8, ThrustCurve::Quadratic { k: 0.8 });
        assert!(lin.abs() < 1e-3, "{lin}");
    }

    #[test]
    fn roll_command_rolls_right_and_beta_matches() {
        let mut p = QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X);
        p.gyro_noise_dps = 0.0;
        p.latency_samples = 0;
        let hover = p.hover_throttle() as f32;
        let mut q = Quad::new(p, 2);
        let mixer = Mixer::new(QUAD_X, ThrustCurve::Linear);
        // 0.1 of roll for 0.2 s: after the motor lag, ω' ≈ β·0.1.
        let mut last = 0.0;
        for i in 0..200 {
            let (_, t) = q.step(0.001, &mixer.mix(hover, [0.1, 0.0, 0.0]));
            if i == 198 {
                last = t.rate_dps[0];
            }
            if i == 199 {
                let accel = (t.rate_dps[0] - last) / 0.001;
                let beta = 10f64.exp();
                assert!((accel / (0.1 * beta) - 1.0).abs() < 0.02, "{accel}");
                assert!(t.rate_dps[1].abs() < 0.5 && t.rate_dps[2].abs() < 0.5);
            }
        }
    }
}
