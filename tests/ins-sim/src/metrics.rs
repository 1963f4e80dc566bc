//! Error metrics between an estimate and the truth: attitude angle, roll/pitch/yaw
//! (wrap-safe, unlike the reference's `fmod` check), position and velocity.

use flight_app::estimation::ins::State;

use crate::trajectory::{Truth, multiply, to_euler};

/// Errors of one estimate against the truth.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Errors {
    /// Total attitude error (deg).
    pub attitude_deg: f64,
    /// Roll error (deg, signed, wrapped).
    pub roll_deg: f64,
    /// Pitch error (deg, signed).
    pub pitch_deg: f64,
    /// Yaw error (deg, signed, wrapped to ±180).
    pub yaw_deg: f64,
    /// Position error per axis (m).
    pub position_m: [f64; 3],
    /// Velocity error per axis (m/s).
    pub velocity_mps: [f64; 3],
}

impl Errors {
    /// Largest |position error| over the axes.
    #[must_use]
    pub fn position_max_m(&self) -> f64 {
        self.position_m.iter().fold(0.0, |a, b| a.max(b.abs()))
    }

    /// Largest |velocity error| over the axes.
    #[must_use]
    pub fn velocity_max_mps(&self) -> f64 {
        self.velocity_mps.iter().fold(0.0, |a, b| a.max(b.abs()))
    }

    /// max(|roll|, |pitch|) error (deg).
    #[must_use]
    pub fn tilt_deg(&self) -> f64 {
        self.roll_deg.abs().max(self.pitch_deg.abs())
    }
}

/// Wraps degrees into (−180, 180].
#[must_use]
pub fn wrap_deg(a: f64) -> f64 {
    let mut a = a % 360.0;
    if a > 180.0 {
        a -= 360.0;
    } else if a <= -180.0 {
        a += 360.0;
    }
    a
}

/// Attitude difference (deg) between two quaternions, sign-agnostic.
#[must_use]
pub fn attitude_angle_deg(a: [f64; 4], b: [f64; 4]) -> f64 {
    let d = multiply([a[0], -a[1], -a[2], -a[3]], b);
    let v = (d[1] * d[1] + d[2] * d[2] + d[3] * d[3]).sqrt();
    (2.0 * v.atan2(d[0].abs())).to_degrees()
}

/// Compares attitude, position and velocity given as plain arrays.
#[must_use]
pub fn compare(
    q: [f64; 4],
    pos: [f64; 3],
    vel: [f64; 3],
    q_ref: [f64; 4],
    pos_ref: [f64; 3],
    vel_ref: [f64; 3],
) -> Errors {
    let e = to_euler(q);
    let t = to_euler(q_ref);
    Errors {
        attitude_deg: attitude_angle_deg(q, q_ref),
        roll_deg: wrap_deg((e[0] - t[0]).to_degrees()),
        pitch_deg: (e[1] - t[1]).to_degrees(),
        yaw_deg: wrap_deg((e[2] - t[2]).to_degrees()),
        position_m: crate::zip3(pos, pos_ref, |a, b| a - b),
        velocity_mps: crate::zip3(vel, vel_ref, |a, b| a - b),
    }
}

/// Errors of `state` against `truth`.
#[must_use]
pub fn errors(state: &State, truth: &Truth) -> Errors {
    compare(
        state.attitude.map(f64::from),
        state.position_ned_m.map(f64::from),
        state.velocity_ned_mps.map(f64::from),
        truth.attitude,
        truth.position_ned_m,
        truth.velocity_ned_mps,
    )
}
