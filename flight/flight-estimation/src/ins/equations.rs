//! The continuous-time process model, its Jacobian blocks and the heading-only magnetometer
//! model with its Jacobian, all hand-derived in `DERIVATION.md` and checked against finite
//! differences in `tests/ins_jacobians.rs`.

use super::STATES;
use crate::math::inv_sqrt;
use crate::quaternion::{Quaternion, ned_to_body};

/// ẋ = f(x, u) (DERIVATION.md §1): `ṗ = v`, `v̇ = R_beᵀ(q)(f − [0,0,ab_z]) + [0,0,g]`,
/// `q̇ = ½ q ⊗ [0, ω − b_g]`, constant biases.
#[must_use]
pub fn derivative(
    x: &[f32; STATES],
    gyro_radps: [f32; 3],
    accel_mps2: [f32; 3],
    gravity_mps2: f32,
) -> [f32; STATES] {
    let [_, _, _, vn, ve, vd, q0, q1, q2, q3, bx, by, bz, ab_z] = *x;
    let [[r11, r12, r13], [r21, r22, r23], [r31, r32, r33]] = ned_to_body([q0, q1, q2, q3]);
    let [fx, fy, fz] = accel_mps2;
    let fz = fz - ab_z;
    let [wx, wy, wz] = [gyro_radps[0] - bx, gyro_radps[1] - by, gyro_radps[2] - bz];
    [
        vn,
        ve,
        vd,
        r11 * fx + r21 * fy + r31 * fz,
        r12 * fx + r22 * fy + r32 * fz,
        r13 * fx + r23 * fy + r33 * fz + gravity_mps2,
        0.5 * (-q1 * wx - q2 * wy - q3 * wz),
        0.5 * (q0 * wx - q3 * wy + q2 * wz),
        0.5 * (q3 * wx + q0 * wy - q1 * wz),
        0.5 * (-q2 * wx + q1 * wy + q0 * wz),
        0.0,
        0.0,
        0.0,
        0.0,
    ]
}

/// The non-trivial blocks of F = ∂f/∂x (the rest is ∂ṗ/∂v = I and zeros), held as the few
/// distinct values they are made of (DERIVATION.md §2): ∂v̇/∂q is four values with signs,
/// ∂q̇/∂q three, ∂q̇/∂b_g four. The covariance prediction applies the blocks to vectors with
/// these values in registers (`*_times_add`); the full matrices are for tests and readers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProcessJacobian {
    /// d1..d4 of DERIVATION.md §2.
    d: [f32; 4],
    /// ∂v̇/∂ab_z = −(third column of R_beᵀ).
    dv_dbaz: [f32; 3],
    /// ½(ω − b_g).
    half_rate: [f32; 3],
    /// ½q.
    half_q: Quaternion,
}

impl ProcessJacobian {
    /// Every block multiplied by `k` (Φ − I = F·dt is `scaled(dt)`).
    #[must_use]
    #[inline(always)]
    pub fn scaled(&self, k: f32) -> Self {
        Self {
            d: self.d.map(|v| v * k),
            dv_dbaz: self.dv_dbaz.map(|v| v * k),
            half_rate: self.half_rate.map(|v| v * k),
            half_q: self.half_q.map(|v| v * k),
        }
    }

    /// acc + (∂v̇/∂q)·δq, summed into `acc` term by term (one multiply-accumulate each).
    #[must_use]
    #[inline(always)]
    pub fn dv_dq_times_add(&self, dq: [f32; 4], acc: [f32; 3]) -> [f32; 3] {
        let [d1, d2, d3, d4] = self.d;
        let [a, b, c, e] = dq;
        let [n, east, down] = acc;
        [
            n + d1 * a + d2 * b + d3 * c + d4 * e,
            east - d4 * a - d3 * b + d2 * c + d1 * e,
            down + d3 * a - d4 * b - d1 * c + d2 * e,
        ]
    }

    /// ∂v̇/∂ab_z.
    #[must_use]
    #[inline(always)]
    pub fn dv_dbaz(&self) -> [f32; 3] {
        self.dv_dbaz
    }

    /// acc + (∂q̇/∂q)·δq = acc + ½Ω(ω − b_g)·δq.
    #[must_use]
    #[inline(always)]
    pub fn dq_dq_times_add(&self, dq: [f32; 4], acc: [f32; 4]) -> [f32; 4] {
        let [hx, hy, hz] = self.half_rate;
        let [a, b, c, e] = dq;
        let [s0, s1, s2, s3] = acc;
        [
            s0 - hx * b - hy * c - hz * e,
            s1 + hx * a + hz * c - hy * e,
            s2 + hy * a - hz * b + hx * e,
            s3 + hz * a + hy * b - hx * c,
        ]
    }

    /// acc + (∂q̇/∂b_g)·δb = acc − ½Ξ(q)·δb.
    #[must_use]
    #[inline(always)]
    pub fn dq_dbg_times_add(&self, db: [f32; 3], acc: [f32; 4]) -> [f32; 4] {
        let [k0, k1, k2, k3] = self.half_q;
        let [x, y, z] = db;
        let [s0, s1, s2, s3] = acc;
        [
            s0 + k1 * x + k2 * y + k3 * z,
            s1 - k0 * x + k3 * y - k2 * z,
            s2 - k3 * x - k0 * y + k1 * z,
            s3 + k2 * x - k1 * y - k0 * z,
        ]
    }

    /// ∂v̇/∂q as a matrix (3×4).
    #[must_use]
    pub fn dv_dq(&self) -> [[f32; 4]; 3] {
        transpose(core::array::from_fn(|m| {
            self.dv_dq_times_add(unit(m), [0.0; 3])
        }))
    }

    /// ∂q̇/∂q as a matrix (4×4).
    #[must_use]
    pub fn dq_dq(&self) -> [[f32; 4]; 4] {
        transpose(core::array::from_fn(|m| {
            self.dq_dq_times_add(unit(m), [0.0; 4])
        }))
    }

    /// ∂q̇/∂b_g as a matrix (4×3).
    #[must_use]
    pub fn dq_dbg(&self) -> [[f32; 3]; 4] {
        transpose(core::array::from_fn(|m| {
            self.dq_dbg_times_add(unit(m), [0.0; 4])
        }))
    }
}

/// The m-th unit vector.
fn unit<const N: usize>(m: usize) -> [f32; N] {
    core::array::from_fn(|i| if i == m { 1.0 } else { 0.0 })
}

/// Columns → matrix.
fn transpose<const R: usize, const C: usize>(columns: [[f32; R]; C]) -> [[f32; C]; R] {
    core::array::from_fn(|r| {
        core::array::from_fn(|c| {
            columns
                .get(c)
                .and_then(|col| col.get(r))
                .copied()
                .unwrap_or(0.0)
        })
    })
}

/// Ξ(q): q ⊗ [0, ω] = Ξ(q)·ω.
#[must_use]
pub fn xi(q: Quaternion) -> [[f32; 3]; 4] {
    let [q0, q1, q2, q3] = q;
    [[-q1, -q2, -q3], [q0, -q3, q2], [q3, q0, -q1], [-q2, q1, q0]]
}

/// F at state `x` with inputs held constant (DERIVATION.md §2).
#[must_use]
#[inline(always)]
pub fn process_jacobian(
    x: &[f32; STATES],
    gyro_radps: [f32; 3],
    accel_mps2: [f32; 3],
) -> ProcessJacobian {
    let [_, _, _, _, _, _, q0, q1, q2, q3, bx, by, bz, ab_z] = *x;
    let [a0, a1, a2] = [accel_mps2[0], accel_mps2[1], accel_mps2[2] - ab_z];
    let [wx, wy, wz] = [gyro_radps[0] - bx, gyro_radps[1] - by, gyro_radps[2] - bz];
    ProcessJacobian {
        d: [
            2.0 * (q0 * a0 - q3 * a1 + q2 * a2),
            2.0 * (q1 * a0 + q2 * a1 + q3 * a2),
            2.0 * (-q2 * a0 + q1 * a1 + q0 * a2),
            2.0 * (-q3 * a0 - q0 * a1 + q1 * a2),
        ],
        dv_dbaz: [
            -2.0 * (q1 * q3 + q0 * q2),
            -2.0 * (q2 * q3 - q0 * q1),
            -(q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3),
        ],
        half_rate: [0.5 * wx, 0.5 * wy, 0.5 * wz],
        half_q: [0.5 * q0, 0.5 * q1, 0.5 * q2, 0.5 * q3],
    }
}

/// The magnetometer reading rotated into the level heading frame with the filter's own roll
/// and pitch (R_aᵀ·m, DERIVATION.md §4). Its horizontal part depends on yaw alone.
#[must_use]
pub fn level_frame_field(q: Quaternion, mag_body: [f32; 3]) -> [f32; 3] {
    let [[_, _, r13], [_, _, r23], [_, _, r33]] = ned_to_body(q);
    // A plain comparison, not f32::max, which the M4F lowers to a libm `fmaxf` call.
    let cos_pitch2 = floor_at(1.0 - r13 * r13, 1e-12);
    let inv_cos_pitch = inv_sqrt(cos_pitch2);
    let cos_pitch = cos_pitch2 * inv_cos_pitch;
    let sin_pitch = -r13;
    let sin_roll = r23 * inv_cos_pitch;
    let cos_roll = r33 * inv_cos_pitch;
    let [m0, m1, m2] = mag_body;
    [
        cos_pitch * m0 + sin_roll * sin_pitch * m1 + cos_roll * sin_pitch * m2,
        cos_roll * m1 - sin_roll * m2,
        -sin_pitch * m0 + sin_roll * cos_pitch * m1 + cos_roll * cos_pitch * m2,
    ]
}

/// Predicted horizontal heading-frame field Rz(ψ)·[Be0, Be1] and its Jacobian ∂/∂q
/// (2×4), DERIVATION.md §4. ψ = atan2(R12, R11) is never evaluated: cos ψ and sin ψ are
/// R11/r and R12/r.
#[must_use]
pub fn heading_field(q: Quaternion, earth_field_ne: [f32; 2]) -> ([f32; 2], [[f32; 4]; 2]) {
    let [q0, q1, q2, q3] = q;
    let r11 = q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3;
    let r12 = 2.0 * (q1 * q2 + q0 * q3);
    let r2 = floor_at(r11 * r11 + r12 * r12, 1e-12);
    let inv_r = inv_sqrt(r2);
    let (cos_yaw, sin_yaw) = (r11 * inv_r, r12 * inv_r);
    let [b0, b1] = earth_field_ne;
    let y6 = b0 * cos_yaw + b1 * sin_yaw;
    let y7 = -b0 * sin_yaw + b1 * cos_yaw;
    // dψ/dq = (R11·dR12 − R12·dR11) / r², with dR11 = 2[q0,q1,−q2,−q3], dR12 = 2[q3,q2,q1,q0].
    let k = 2.0 / r2;
    let dpsi = [
        k * (r11 * q3 - r12 * q0),
        k * (r11 * q2 - r12 * q1),
        k * (r11 * q1 + r12 * q2),
        k * (r11 * q0 + r12 * q3),
    ];
    ([y6, y7], [dpsi.map(|d| y7 * d), dpsi.map(|d| -y6 * d)])
}

/// `max(x, floor)` for finite inputs without a libm call (a NaN gives `floor`).
#[inline(always)]
fn floor_at(x: f32, floor: f32) -> f32 {
    if x > floor { x } else { floor }
}
