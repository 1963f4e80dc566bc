//! Attitude quaternion helpers. Convention (as the Tau Labs INS): `q = [q0, q1, q2, q3]`,
//! q0 scalar, rotating body FRD to NED; [`ned_to_body`] is R_be(q), the NED→body DCM.

use crate::math::{inv_sqrt, sin_cos};

/// Attitude quaternion `[w, x, y, z]`, body FRD → NED.
pub type Quaternion = [f32; 4];

/// The identity attitude (level, facing north).
pub const IDENTITY: Quaternion = [1.0, 0.0, 0.0, 0.0];

/// R_be(q): rows are the NED axes expressed in body coordinates (`estimation/ins/DERIVATION.md`
/// §0).
#[must_use]
pub fn ned_to_body(q: Quaternion) -> [[f32; 3]; 3] {
    let [q0, q1, q2, q3] = q;
    let (q00, q11, q22, q33) = (q0 * q0, q1 * q1, q2 * q2, q3 * q3);
    [
        [
            q00 + q11 - q22 - q33,
            2.0 * (q1 * q2 + q0 * q3),
            2.0 * (q1 * q3 - q0 * q2),
        ],
        [
            2.0 * (q1 * q2 - q0 * q3),
            q00 - q11 + q22 - q33,
            2.0 * (q2 * q3 + q0 * q1),
        ],
        [
            2.0 * (q1 * q3 + q0 * q2),
            2.0 * (q2 * q3 - q0 * q1),
            q00 - q11 - q22 + q33,
        ],
    ]
}

/// Rotates a body vector into NED: R_beᵀ·v.
#[must_use]
pub fn body_to_ned_vector(q: Quaternion, v: [f32; 3]) -> [f32; 3] {
    let [[r11, r12, r13], [r21, r22, r23], [r31, r32, r33]] = ned_to_body(q);
    let [x, y, z] = v;
    [
        r11 * x + r21 * y + r31 * z,
        r12 * x + r22 * y + r32 * z,
        r13 * x + r23 * y + r33 * z,
    ]
}

/// Rotates a NED vector into body axes: R_be·v.
#[must_use]
pub fn ned_to_body_vector(q: Quaternion, v: [f32; 3]) -> [f32; 3] {
    let [r1, r2, r3] = ned_to_body(q);
    let dot = |r: [f32; 3]| r[0] * v[0] + r[1] * v[1] + r[2] * v[2];
    [dot(r1), dot(r2), dot(r3)]
}

/// Hamilton product a ⊗ b.
#[must_use]
pub fn multiply(a: Quaternion, b: Quaternion) -> Quaternion {
    let [a0, a1, a2, a3] = a;
    let [b0, b1, b2, b3] = b;
    [
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
        a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
        a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
    ]
}

/// q / |q| with a fully converged inverse square root; the identity for a zero quaternion.
#[must_use]
pub fn normalized(q: Quaternion) -> Quaternion {
    let n2 = q.iter().map(|c| c * c).sum::<f32>();
    if n2 <= f32::MIN_POSITIVE || !n2.is_finite() {
        return IDENTITY;
    }
    let s = inv_sqrt(n2);
    // The scalar part is kept non-negative so equal attitudes compare equal.
    let s = if q[0] < 0.0 { -s } else { s };
    q.map(|c| c * s)
}

/// Rotation by a body-frame rotation vector θ (rad) over one step: q ⊗ δq(θ), using the
/// third-order series of δq = [cos(|θ|/2), sin(|θ|/2)·θ/|θ|] (no trig in the hot path).
#[must_use]
pub fn rotate_by_body_vector(q: Quaternion, theta_rad: [f32; 3]) -> Quaternion {
    let half = theta_rad.map(|t| 0.5 * t);
    let n2 = half[0] * half[0] + half[1] * half[1] + half[2] * half[2];
    let s = 1.0 - n2 * (1.0 / 6.0);
    let dq = [
        1.0 - 0.5 * n2 + n2 * n2 * (1.0 / 24.0),
        half[0] * s,
        half[1] * s,
        half[2] * s,
    ];
    multiply(q, dq)
}

/// (roll, pitch, yaw) in radians, Tau Labs `quat_rpy` convention (cold path: uses libm).
#[must_use]
pub fn to_euler(q: Quaternion) -> [f32; 3] {
    let [[r11, r12, r13], [_, _, r23], [_, _, r33]] = ned_to_body(q);
    [
        libm::atan2f(r23, r33),
        libm::asinf((-r13).clamp(-1.0, 1.0)),
        libm::atan2f(r12, r11),
    ]
}

/// Quaternion from (roll, pitch, yaw) in radians, ZYX order.
#[must_use]
pub fn from_euler(roll_rad: f32, pitch_rad: f32, yaw_rad: f32) -> Quaternion {
    let (sr, cr) = sin_cos(0.5 * roll_rad);
    let (sp, cp) = sin_cos(0.5 * pitch_rad);
    let (sy, cy) = sin_cos(0.5 * yaw_rad);
    normalized([
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ])
}

/// Angle of the rotation between two attitudes (rad), sign-agnostic.
#[must_use]
pub fn angle_between(a: Quaternion, b: Quaternion) -> f32 {
    // 2·atan2(|vec(a*⊗b)|, |scalar|) stays accurate for tiny angles, unlike acos.
    let [w, x, y, z] = multiply([a[0], -a[1], -a[2], -a[3]], b);
    2.0 * libm::atan2f(libm::sqrtf(x * x + y * y + z * z), w.abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_round_trip() {
        let q = from_euler(0.3, -0.2, 2.5);
        let [r, p, y] = to_euler(q);
        assert!((r - 0.3).abs() < 1e-5 && (p + 0.2).abs() < 1e-5 && (y - 2.5).abs() < 1e-5);
    }

    #[test]
    fn yaw_turns_north_towards_east() {
        // Facing east (yaw +90°), the body x axis points east in NED.
        let q = from_euler(0.0, 0.0, core::f32::consts::FRAC_PI_2);
        let [n, e, d] = body_to_ned_vector(q, [1.0, 0.0, 0.0]);
        assert!(n.abs() < 1e-6 && (e - 1.0).abs() < 1e-6 && d.abs() < 1e-6);
        let b = ned_to_body_vector(q, [n, e, d]);
        assert!((b[0] - 1.0).abs() < 1e-6);
    }

    #[test]
    fn small_rotation_matches_exact_rotation() {
        let q = from_euler(0.1, 0.2, 0.3);
        let step = rotate_by_body_vector(q, [0.0, 0.0, 0.02]);
        let exact = multiply(q, from_euler(0.0, 0.0, 0.02));
        assert!(angle_between(step, exact) < 1e-6);
    }
}
