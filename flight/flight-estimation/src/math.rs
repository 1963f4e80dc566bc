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

/// `a.min(b)` with `f32::min`'s NaN rule (a NaN argument yields the other one) as two
/// compares: the M4F has no VMINNM, so `f32::min` is a call into compiler-builtins' `fminf`
/// (≈ 12 instructions with the call).
#[must_use]
#[inline(always)]
pub fn min(a: f32, b: f32) -> f32 {
    if b < a || a.is_nan() { b } else { a }
}

/// `a.max(b)` with `f32::max`'s NaN rule, as two compares (see [`min`]).
#[must_use]
#[inline(always)]
pub fn max(a: f32, b: f32) -> f32 {
    if b > a || a.is_nan() { b } else { a }
}

/// `x` limited to ±|`limit`|: `x.clamp(-limit, limit)` for every limit `clamp` accepts, and
/// for the ones it panics on (a negative limit: crossed bounds; NaN) no panic path at all —
/// the limit's magnitude counts, a NaN limit leaves `x` as it is, a NaN `x` stays NaN (as
/// `clamp` returns it). Two compares, no call.
#[must_use]
#[inline(always)]
pub fn clamp_abs(x: f32, limit: f32) -> f32 {
    let limit = limit.abs();
    if x < -limit {
        -limit
    } else if x > limit {
        limit
    } else {
        x
    }
}

/// `v.clamp(lo, hi)` without its panic: `f32::clamp` asserts `lo ≤ hi` and, unless the
/// bounds are constants, formats them with `Debug` for the message — which alone links
/// core's float formatting into the image (≈ 10 KB of flash, issue 33). A NaN `v` stays
/// NaN, as with `f32::clamp`; bounds in the wrong order give one of them, not a panic.
#[must_use]
#[inline(always)]
pub fn clamp(v: f32, lo: f32, hi: f32) -> f32 {
    if v < lo {
        lo
    } else if v > hi {
        hi
    } else {
        v
    }
}

/// Wraps an angle to (−π, π].
#[must_use]
pub fn wrap_pi(angle_rad: f32) -> f32 {
    // Already in range (every atan2 result but −π): `%` would return it unchanged, and it is
    // a soft-float `fmodf` call on the M4F.
    if angle_rad > -core::f32::consts::PI && angle_rad <= core::f32::consts::PI {
        return angle_rad;
    }
    let two_pi = 2.0 * core::f32::consts::PI;
    let mut a = angle_rad % two_pi;
    if a > core::f32::consts::PI {
        a -= two_pi;
    } else if a <= -core::f32::consts::PI {
        a += two_pi;
    }
    a
}

/// `(sin x, cos x)` for the angles this firmware forms (a few turns at most), within
/// 2 ulp of libm's `sinf`/`cosf` for |x| ≤ 8 192 rad; beyond, the reduction loses bits
/// (the result stays in [−1, 1]); NaN and ±∞ give NaN. libm's f32 sine and cosine carry a
/// reduction for any argument (≈ 4 KB of flash, issue 33) that no angle here needs.
#[must_use]
// Out of line: it runs at setup and on a new home, and inlined into `GpsAiding::fuse` it
// cost that hot path 67 instructions of register pressure.
#[inline(never)]
pub fn sin_cos(x: f32) -> (f32, f32) {
    // Quadrant n = round(x·2/π), then r = x − n·π/2 in three parts (Cody–Waite: the first
    // two have few enough bits that n times them is exact for |n| < 2¹³), |r| ≤ π/4.
    const PIO2_HI: f32 = 1.570_312_5;
    const PIO2_MID: f32 = 4.837_513e-4;
    const PIO2_LO: f32 = 7.549_79e-8;
    let q = x * core::f32::consts::FRAC_2_PI;
    let n = (if q >= 0.0 { q + 0.5 } else { q - 0.5 }) as i32;
    let nf = n as f32;
    let r = ((x - nf * PIO2_HI) - nf * PIO2_MID) - nf * PIO2_LO;
    let z = r * r;
    // Minimax polynomials on [−π/4, π/4] (the Cephes single-precision coefficients).
    let sin = r + r * z * (-1.666_665_5e-1 + z * (8.332_161e-3 + z * -1.951_529_6e-4));
    let cos = 1.0 - 0.5 * z + z * z * (4.166_664_6e-2 + z * (-1.388_731_6e-3 + z * 2.443_315_7e-5));
    match n & 3 {
        0 => (sin, cos),
        1 => (cos, -sin),
        2 => (-sin, -cos),
        _ => (-cos, sin),
    }
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

    /// Values around the branches of the helpers, with NaN and the infinities.
    const EDGES: [f32; 11] = [
        f32::NAN,
        f32::NEG_INFINITY,
        -3.5,
        -core::f32::consts::PI,
        -1.0,
        -0.0,
        0.0,
        1.0,
        core::f32::consts::PI,
        7.0,
        f32::INFINITY,
    ];

    #[test]
    fn min_and_max_match_the_std_ones_bit_for_bit_nan_included() {
        for a in EDGES {
            for b in EDGES {
                // ±0 may come out either way from the std ones; compare by value there.
                let same = |x: f32, y: f32| x.to_bits() == y.to_bits() || (x == 0.0 && y == 0.0);
                assert!(same(min(a, b), a.min(b)), "min({a}, {b})");
                assert!(same(max(a, b), a.max(b)), "max({a}, {b})");
            }
        }
    }

    #[test]
    fn wrap_pi_fast_path_returns_what_the_remainder_returns() {
        let slow = |a: f32| {
            let two_pi = 2.0 * core::f32::consts::PI;
            let mut r = a % two_pi;
            if r > core::f32::consts::PI {
                r -= two_pi;
            } else if r <= -core::f32::consts::PI {
                r += two_pi;
            }
            r
        };
        for k in -4000..=4000 {
            let a = k as f32 * 1e-3;
            assert_eq!(wrap_pi(a).to_bits(), slow(a).to_bits(), "{a}");
        }
        for a in EDGES.into_iter().filter(|a| a.is_finite()) {
            assert_eq!(wrap_pi(a).to_bits(), slow(a).to_bits(), "{a}");
        }
    }

    #[test]
    fn wrap_pi_maps_into_range() {
        assert!((wrap_pi(3.0 * core::f32::consts::PI) - core::f32::consts::PI).abs() < 1e-5);
        assert!((wrap_pi(-0.5) + 0.5).abs() < 1e-7);
        assert!((wrap_pi(7.0) - (7.0 - 2.0 * core::f32::consts::PI)).abs() < 1e-5);
    }

    #[test]
    fn sin_cos_matches_libm_within_two_ulp() {
        // The spacing of f32 values at |b|: one ulp.
        let ulp = |b: f32| f32::from_bits(b.abs().to_bits() + 1) - b.abs();
        let close = |a: f32, b: f32| (a - b).abs() <= 2.0 * ulp(b);
        for k in -200_000..=200_000 {
            let x = k as f32 * 1e-4;
            let (s, c) = sin_cos(x);
            assert!(close(s, libm::sinf(x)), "sin {x}: {s} vs {}", libm::sinf(x));
            assert!(close(c, libm::cosf(x)), "cos {x}: {c} vs {}", libm::cosf(x));
        }
        for x in [100.0_f32, 1_000.5, -4_321.0, 8_192.0] {
            let (s, c) = sin_cos(x);
            assert!(close(s, libm::sinf(x)), "sin {x}");
            assert!(close(c, libm::cosf(x)), "cos {x}");
        }
    }

    #[test]
    fn sin_cos_is_exact_at_zero_odd_even_and_nan_outside_the_reals() {
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        for k in 1..1000 {
            let x = k as f32 * 7.3e-3;
            let (s, c) = sin_cos(x);
            assert_eq!(sin_cos(-x), (-s, c), "{x}");
        }
        for x in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let (s, c) = sin_cos(x);
            assert!(s.is_nan() && c.is_nan(), "{x}");
        }
    }
}
