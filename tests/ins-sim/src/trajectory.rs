//! Truth trajectories, generated kinematically from body rates and specific forces (as the
//! Tau Labs `simulation.py` does) so the truth is exactly consistent with an ideal IMU.
//! Integration runs in f64 with an exact rotation per step.

use flight_app::estimation::GRAVITY_MPS2;

/// Truth at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Time since start (s).
    pub time_s: f64,
    /// Position NED (m).
    pub position_ned_m: [f64; 3],
    /// Velocity NED (m/s).
    pub velocity_ned_mps: [f64; 3],
    /// Attitude body → NED `[w, x, y, z]`.
    pub attitude: [f64; 4],
    /// True body rate (rad/s).
    pub gyro_radps: [f64; 3],
    /// True specific force (m/s², body).
    pub accel_mps2: [f64; 3],
}

/// What the craft does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// Still, at the initial pose.
    Static,
    /// `fly_circle` (DERIVATION.md §7): 5 s straight and climbing-down, then a level 18 s circle of
    /// ≈ 8.2 m radius, with a vertical stop between 20 and 25 s.
    Circle,
    /// `rock_and_turn` (DERIVATION.md §7): 5 °/s yaw, vertical pulses, then a pitch rocking at 0.1
    /// Hz from 30 s; the specific force stays body-fixed so the craft drifts away.
    RockAndTurn,
    /// Hovering in place while rotating about all three axes (rates up to ~30 °/s): the
    /// specific force is gravity only, so an accelerometer sees true "down" at all times.
    Wobble,
}

impl Motion {
    /// (body rate rad/s, body specific force m/s²) at time `t` for attitude `q`.
    #[must_use]
    pub fn inputs(self, t: f64, q: [f64; 4]) -> ([f64; 3], [f64; 3]) {
        let g = f64::from(GRAVITY_MPS2);
        match self {
            Self::Static => ([0.0; 3], rotate_to_body(q, [0.0, 0.0, -g])),
            Self::Wobble => (
                [0.5 * (0.5 * t).sin(), 0.3 * (0.7 * t).cos(), 0.2],
                rotate_to_body(q, [0.0, 0.0, -g]),
            ),
            Self::Circle => {
                if t < 5.0 {
                    ([0.0; 3], [0.0, 0.0, -g + 0.5])
                } else {
                    let fz = if t > 20.0 && t < 25.0 { -g - 0.5 } else { -g };
                    ([0.0, 0.0, (-20.0f64).to_radians()], [0.0, 1.0, fz])
                }
            }
            Self::RockAndTurn => {
                let fz = if t < 5.0 {
                    -g + 0.5
                } else if t > 20.0 && t < 25.0 {
                    -g - 0.5
                } else {
                    -g
                };
                let wy = if t > 30.0 {
                    (10.0 * (2.0 * std::f64::consts::PI * 0.1 * t).sin()).to_radians()
                } else {
                    0.0
                };
                ([0.0, wy, 5f64.to_radians()], [0.0, 0.0, fz])
            }
        }
    }
}

/// A trajectory being integrated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trajectory {
    motion: Motion,
    truth: Truth,
}

impl Trajectory {
    /// Starts `motion` at the given pose and velocity.
    #[must_use]
    pub fn new(
        motion: Motion,
        position_ned_m: [f64; 3],
        velocity_ned_mps: [f64; 3],
        attitude: [f64; 4],
    ) -> Self {
        let attitude = normalize(attitude);
        let (gyro_radps, accel_mps2) = motion.inputs(0.0, attitude);
        Self {
            motion,
            truth: Truth {
                time_s: 0.0,
                position_ned_m,
                velocity_ned_mps,
                attitude,
                gyro_radps,
                accel_mps2,
            },
        }
    }

    /// The truth now.
    #[must_use]
    pub fn truth(&self) -> &Truth {
        &self.truth
    }

    /// Advances by `dt_s` (inputs held over the step, exact rotation, trapezoidal position).
    pub fn advance(&mut self, dt_s: f64) {
        let t = &mut self.truth;
        let (w, f) = self.motion.inputs(t.time_s, t.attitude);
        let g = f64::from(GRAVITY_MPS2);
        let a = rotate_to_ned(t.attitude, f);
        let a = [a[0], a[1], a[2] + g];
        let v_old = t.velocity_ned_mps;
        t.velocity_ned_mps = crate::zip3(v_old, a, |v, a| v + a * dt_s);
        let v_mean = crate::zip3(v_old, t.velocity_ned_mps, |a, b| 0.5 * (a + b));
        t.position_ned_m = crate::zip3(t.position_ned_m, v_mean, |p, v| p + v * dt_s);
        t.attitude = normalize(multiply(
            t.attitude,
            exp_rotation([w[0] * dt_s, w[1] * dt_s, w[2] * dt_s]),
        ));
        t.time_s += dt_s;
        let (w, f) = self.motion.inputs(t.time_s, t.attitude);
        t.gyro_radps = w;
        t.accel_mps2 = f;
    }
}

/// Quaternion of a rotation vector.
#[must_use]
pub fn exp_rotation(theta: [f64; 3]) -> [f64; 4] {
    let n = (theta[0] * theta[0] + theta[1] * theta[1] + theta[2] * theta[2]).sqrt();
    if n < 1e-15 {
        return [1.0, 0.5 * theta[0], 0.5 * theta[1], 0.5 * theta[2]];
    }
    let (s, c) = (0.5 * n).sin_cos();
    [c, s * theta[0] / n, s * theta[1] / n, s * theta[2] / n]
}

/// Hamilton product.
#[must_use]
pub fn multiply(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// q/|q|.
#[must_use]
pub fn normalize(q: [f64; 4]) -> [f64; 4] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    q.map(|c| c / n)
}

/// Body vector → NED.
#[must_use]
pub fn rotate_to_ned(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let p = multiply(
        multiply(q, [0.0, v[0], v[1], v[2]]),
        [q[0], -q[1], -q[2], -q[3]],
    );
    [p[1], p[2], p[3]]
}

/// NED vector → body.
#[must_use]
pub fn rotate_to_body(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    rotate_to_ned([q[0], -q[1], -q[2], -q[3]], v)
}

/// Quaternion from roll, pitch, yaw (rad, ZYX).
#[must_use]
pub fn from_euler(roll: f64, pitch: f64, yaw: f64) -> [f64; 4] {
    let (sr, cr) = (0.5 * roll).sin_cos();
    let (sp, cp) = (0.5 * pitch).sin_cos();
    let (sy, cy) = (0.5 * yaw).sin_cos();
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

/// (roll, pitch, yaw) in rad.
#[must_use]
pub fn to_euler(q: [f64; 4]) -> [f64; 3] {
    let [q0, q1, q2, q3] = q;
    let r11 = q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3;
    let r12 = 2.0 * (q1 * q2 + q0 * q3);
    let r13 = 2.0 * (q1 * q3 - q0 * q2);
    let r23 = 2.0 * (q2 * q3 + q0 * q1);
    let r33 = q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3;
    [
        r23.atan2(r33),
        (-r13).clamp(-1.0, 1.0).asin(),
        r12.atan2(r11),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_has_the_reference_radius_and_period() {
        // GIVEN the circle flight starting at 2.85 m/s south
        let mut traj = Trajectory::new(
            Motion::Circle,
            [0.0; 3],
            [-2.85, 0.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
        );
        let dt = 0.001;
        // WHEN flown for 30 s (5 s straight, then circling)
        let mut min_n: f64 = f64::MAX;
        let mut max_n: f64 = f64::MIN;
        for k in 0..30_000 {
            traj.advance(dt);
            if k > 6000 {
                min_n = min_n.min(traj.truth().position_ned_m[0]);
                max_n = max_n.max(traj.truth().position_ned_m[0]);
            }
        }
        // THEN the horizontal diameter is 2·v/ω ≈ 16.3 m and the descent has stopped
        let diameter = max_n - min_n;
        assert!(
            (diameter - 2.0 * 2.85 / 20f64.to_radians()).abs() < 0.3,
            "diameter {diameter}"
        );
        assert!(traj.truth().velocity_ned_mps[2].abs() < 1e-6);
    }
}
