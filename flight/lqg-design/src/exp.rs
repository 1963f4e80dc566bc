//! f64 `exp` and `expm1` for the gain design, small rather than fast: one range reduction
//! x = k·ln 2 + r (|r| ≤ ln 2 / 2) and one Taylor series of expm1(r). In soft-float on the
//! Cortex-M4F libm's pair was 2.2 KB of flash for a handful of calls per design; this is a
//! few hundred bytes, within 2 ulp of the correctly rounded result over the whole range
//! (the tests measure it against std).

/// ln 2 split so that k·`LN2_HI` is exact for |k| < 2²⁰ (its low 32 bits are zero).
const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
/// ln 2 − `LN2_HI`.
const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
/// 1 / ln 2.
const INV_LN2: f64 = core::f64::consts::LOG2_E;
/// Terms of the series: |r|¹⁸/18! < 2⁻⁵³·|r| for |r| ≤ ln 2 / 2.
const TERMS: f64 = 18.0;
/// 1.5·2⁵²: a double below 2⁵¹ plus this is rounded to an integer its low bits hold.
const SHIFTER: f64 = 6_755_399_441_055_744.0;
/// Above this the result is ∞: 1023.5·ln 2, the last x whose k is 1023 (exp itself
/// overflows at 709.78; nothing here comes near either).
const OVERFLOW: f64 = 709.43;
/// Below this exp is under f64's smallest normal (returned as 0, expm1 as −1).
const UNDERFLOW: f64 = -708.0;

/// expm1(r) = r·(1 + r/2·(1 + r/3·(…))) for |r| ≤ ln 2 / 2, where every factor is
/// near 1 and nothing cancels.
fn series(r: f64) -> f64 {
    let (mut acc, mut n) = (1.0, TERMS);
    while n > 1.5 {
        acc = 1.0 + r / n * acc;
        n -= 1.0;
    }
    r * acc
}

/// x = k·ln 2 + r: (2^k, r). Adding [`SHIFTER`] rounds x/ln 2 to the nearest integer k and
/// leaves k in the low bits (two's complement): no float–integer conversion.
fn reduce(x: f64) -> (f64, f64) {
    let shifted = x * INV_LN2 + SHIFTER;
    let kf = shifted - SHIFTER;
    let r = (x - kf * LN2_HI) - kf * LN2_LO;
    // −1021 ≤ k ≤ 1023 between UNDERFLOW and OVERFLOW, a normal 2^k.
    let k = i64::from(shifted.to_bits() as u32 as i32);
    let two_k = f64::from_bits(((1023 + k) as u64) << 52);
    (two_k, r)
}

/// (eˣ, eˣ − 1) from one reduction and one series: 2^k·(1 + expm1(r)) and
/// 2^k·expm1(r) + (2^k − 1). For |x| < ln 2 / 2, k = 0 and the second is the series
/// itself; beyond, |eˣ − 1| > 0.29 and the sum cancels nothing.
pub fn exp_and_exp_m1(x: f64) -> (f64, f64) {
    if x > OVERFLOW {
        return (f64::INFINITY, f64::INFINITY);
    }
    if x < UNDERFLOW {
        return (0.0, -1.0);
    }
    let (two_k, r) = reduce(x);
    let s = series(r);
    (two_k * (1.0 + s), two_k * s + (two_k - 1.0))
}

/// eˣ.
pub fn exp(x: f64) -> f64 {
    exp_and_exp_m1(x).0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// |got − want| in units of want's last place.
    fn ulps(got: f64, want: f64) -> f64 {
        let ulp = f64::from_bits(want.abs().to_bits() + 1) - want.abs();
        (got - want).abs() / ulp
    }

    fn arguments() -> Vec<f64> {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5f64.ln(),
            2f64.ln(),
            0.34657,
            0.34658,
            -0.34658,
        ];
        let mut m = 1e-300;
        while m < 709.0 {
            for f in [1.0, 1.3, 2.7, 5.1] {
                xs.extend([m * f, -m * f]);
            }
            m *= 1.7;
        }
        xs.retain(|x| x.abs() < 708.0);
        xs
    }

    #[test]
    fn expm1_within_two_ulp_of_std() {
        let worst = arguments()
            .into_iter()
            .map(|x| ulps(exp_and_exp_m1(x).1, x.exp_m1()))
            .fold(0.0, f64::max);
        assert!(worst <= 2.0, "{worst}");
    }

    #[test]
    fn exp_within_two_ulp_of_std() {
        let worst = arguments()
            .into_iter()
            .filter(|x| x.exp() > f64::MIN_POSITIVE)
            .map(|x| ulps(exp(x), x.exp()))
            .fold(0.0, f64::max);
        assert!(worst <= 2.0, "{worst}");
    }

    #[test]
    fn edges() {
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp_and_exp_m1(0.0), (1.0, 0.0));
        assert_eq!(exp(800.0), f64::INFINITY);
        assert!(ulps(exp(709.4), 709.4f64.exp()) <= 2.0);
        assert!(ulps(exp(-707.9), (-707.9f64).exp()) <= 2.0);
        assert_eq!(exp(-800.0), 0.0);
        assert_eq!(exp_and_exp_m1(-800.0), (0.0, -1.0));
        let (e, e_m1) = exp_and_exp_m1(f64::NAN);
        assert!(e.is_nan() && e_m1.is_nan());
    }
}
