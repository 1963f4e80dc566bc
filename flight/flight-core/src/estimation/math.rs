//! Small f32 helpers for the hot paths. The M4F has no hardware `atan2`/`sin`, and libm's f32
//! functions go through software double precision there, so the filters use these instead;
//! libm is only used in cold paths (initialisation, resets).

/// 1/√x for x > 0: the classic bit-level first guess refined by three Newton steps, which
/// brings the relative error below 1e-7 (f32 resolution) for every normal input.
#[must_use]
pub fn inv_sqrt(x: f32) -> f32 {
    let half = 0.5 * x;
    let mut y = f32::from_bits(0x5f37_59df_u32.wrapping_sub(x.to_bits() >> 1));
    y *= 1.5 - half * y * y;
    y *= 1.5 - half * y * y;
    y *= 1.5 - half * y * y;
    y
}

/// √x for x ≥ 0 (0 for 0 and for negative inputs).
#[must_use]
pub fn sqrt(x: f32) -> f32 {
    if x > 0.0 { x * inv_sqrt(x) } else { 0.0 }
}

/// Squared Euclidean norm of a 3-vector.
#[must_use]
pub fn norm_squared(v: [f32; 3]) -> f32 {
    let [x, y, z] = v;
    x * x + y * y + z * z
}

/// Wraps an angle to (−π, π].
#[must_use]
pub fn wrap_pi(angle_rad: f32) -> f32 {
    let two_pi = 2.0 * core::f32::consts::PI;
    let mut a = angle_rad % two_pi;
    if a > core::f32::consts::PI {
        a -= two_pi;
    } else if a <= -core::f32::consts::PI {
        a += two_pi;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inv_sqrt_is_accurate_over_many_decades() {
        for e in -20..20 {
            for m in [1.0_f32, 1.37, 2.0, 3.9, 7.77] {
                let x = m * 10f32.powi(e);
                let rel = (inv_sqrt(x) * x.sqrt() - 1.0).abs();
                assert!(rel < 2e-7, "x={x} rel={rel}");
            }
        }
    }

    #[test]
    fn wrap_pi_maps_into_range() {
        assert!((wrap_pi(3.0 * core::f32::consts::PI) - core::f32::consts::PI).abs() < 1e-5);
        assert!((wrap_pi(-0.5) + 0.5).abs() < 1e-7);
        assert!((wrap_pi(7.0) - (7.0 - 2.0 * core::f32::consts::PI)).abs() < 1e-5);
    }
}
