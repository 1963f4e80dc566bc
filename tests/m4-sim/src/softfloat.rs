//! Single-precision arithmetic exactly as the ARMv7-M ARM's pseudocode defines it (A2.5
//! "Floating-point data types and arithmetic": `FPUnpack`, `FPProcessNaNs`, `FPRound`,
//! `FPAdd`, `FPMul`, `FPMulAdd`, `FPDiv`, `FPSqrt`, `FPCompare`, `FPToFixed`,
//! `FixedToFP`, the half-precision conversions), in integer arithmetic: every result is
//! computed exactly (or with a sticky bit) and rounded once, in the FPSCR's rounding mode,
//! with its flush-to-zero and default-NaN modes and cumulative exception flags. No host
//! floating point decides a result.

/// FPSCR bits.
pub(crate) mod fpscr {
    pub const IOC: u32 = 1 << 0;
    pub const DZC: u32 = 1 << 1;
    pub const OFC: u32 = 1 << 2;
    pub const UFC: u32 = 1 << 3;
    pub const IXC: u32 = 1 << 4;
    pub const IDC: u32 = 1 << 7;
    pub const FZ: u32 = 1 << 24;
    pub const DN: u32 = 1 << 25;
    pub const AHP: u32 = 1 << 26;
    pub const RMODE_SHIFT: u32 = 22;
}

/// The default NaN of single precision.
pub(crate) const DEFAULT_NAN: u32 = 0x7FC0_0000;
const DEFAULT_NAN_HALF: u32 = 0x7E00;

/// Rounding modes (FPSCR.RMode).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rounding {
    Nearest,
    PlusInf,
    MinusInf,
    Zero,
}

impl Rounding {
    pub fn of(fpscr: u32) -> Self {
        match fpscr >> fpscr::RMODE_SHIFT & 3 {
            0 => Rounding::Nearest,
            1 => Rounding::PlusInf,
            2 => Rounding::MinusInf,
            _ => Rounding::Zero,
        }
    }
}

/// `FPType`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Zero,
    Finite,
    Inf,
    QNaN,
    SNaN,
}

/// An unpacked operand: `value = (-1)^sign × mant × 2^exp`.
#[derive(Clone, Copy, Debug)]
struct Val {
    kind: Kind,
    sign: bool,
    mant: u128,
    exp: i32,
    bits: u32,
}

impl Val {
    fn is_nan(&self) -> bool {
        matches!(self.kind, Kind::QNaN | Kind::SNaN)
    }
}

/// `FPUnpack` for single precision (flush-to-zero of denormal inputs sets IDC).
fn unpack(bits: u32, fpscr: &mut u32) -> Val {
    let sign = bits >> 31 != 0;
    let e = (bits >> 23 & 0xFF) as i32;
    let f = bits & 0x7F_FFFF;
    let (kind, mant, exp) = match e {
        0 if f == 0 => (Kind::Zero, 0, 0),
        0 if *fpscr & fpscr::FZ != 0 => {
            *fpscr |= fpscr::IDC;
            (Kind::Zero, 0, 0)
        }
        0 => (Kind::Finite, u128::from(f), -149),
        0xFF if f == 0 => (Kind::Inf, 0, 0),
        0xFF if f & (1 << 22) != 0 => (Kind::QNaN, 0, 0),
        0xFF => (Kind::SNaN, 0, 0),
        _ => (Kind::Finite, u128::from(f | 1 << 23), e - 150),
    };
    Val {
        kind,
        sign,
        mant,
        exp,
        bits,
    }
}

/// `FPProcessNaN`: the NaN quietened (Invalid for a signalling one), or the default NaN.
fn process_nan(v: &Val, fpscr: &mut u32) -> u32 {
    if v.kind == Kind::SNaN {
        *fpscr |= fpscr::IOC;
    }
    if *fpscr & fpscr::DN != 0 {
        DEFAULT_NAN
    } else {
        v.bits | 1 << 22
    }
}

/// `FPProcessNaNs`/`FPProcessNaNs3`: signalling NaNs first, then quiet, in operand order.
fn process_nans(ops: &[&Val], fpscr: &mut u32) -> Option<u32> {
    let pick = ops
        .iter()
        .find(|v| v.kind == Kind::SNaN)
        .or_else(|| ops.iter().find(|v| v.kind == Kind::QNaN))?;
    Some(process_nan(pick, fpscr))
}

fn invalid(fpscr: &mut u32) -> u32 {
    *fpscr |= fpscr::IOC;
    DEFAULT_NAN
}

fn zero(sign: bool) -> u32 {
    u32::from(sign) << 31
}

fn inf(sign: bool) -> u32 {
    u32::from(sign) << 31 | 0x7F80_0000
}

/// The destination format of `FPRound`.
#[derive(Clone, Copy)]
struct Format {
    exp_bits: u32,
    frac_bits: u32,
    /// Half precision with FPSCR.AHP: no infinities or NaNs, and no flush-to-zero.
    half: bool,
}

const SINGLE: Format = Format {
    exp_bits: 8,
    frac_bits: 23,
    half: false,
};
const HALF: Format = Format {
    exp_bits: 5,
    frac_bits: 10,
    half: true,
};

/// `FPRound`: rounds `(-1)^sign × (mant + f) × 2^exp` (with `0 < f < 1` when `sticky`,
/// `f = 0` otherwise; `mant > 0`) to the format, in `mode`.
fn round(
    fmt: Format,
    sign: bool,
    mant: u128,
    exp: i32,
    sticky: bool,
    mode: Rounding,
    fpscr: &mut u32,
) -> u32 {
    let min_exp = 2 - (1i32 << (fmt.exp_bits - 1));
    let f = fmt.frac_bits as i32;
    let msb = 127 - mant.leading_zeros() as i32;
    let exponent = exp + msb;
    let sign_bit = u32::from(sign) << (fmt.exp_bits + fmt.frac_bits);
    if !fmt.half && *fpscr & fpscr::FZ != 0 && exponent < min_exp {
        *fpscr |= fpscr::UFC;
        return sign_bit;
    }
    let mut biased = (exponent - min_exp + 1).max(0);
    let unit = if biased == 0 {
        min_exp - f
    } else {
        exponent - f
    };
    let shift = unit - exp;
    let (mut int_mant, gt_half, eq_half, inexact) = if shift <= 0 {
        (mant << (-shift).min(127), false, false, sticky)
    } else if shift >= 128 {
        (0, false, false, true)
    } else {
        let rem = mant & ((1u128 << shift) - 1);
        let half = 1u128 << (shift - 1);
        (
            mant >> shift,
            rem > half || (rem == half && sticky),
            rem == half && !sticky,
            rem != 0 || sticky,
        )
    };
    if biased == 0 && inexact {
        *fpscr |= fpscr::UFC;
    }
    let up = match mode {
        Rounding::Nearest => gt_half || (eq_half && int_mant & 1 != 0),
        Rounding::PlusInf => inexact && !sign,
        Rounding::MinusInf => inexact && sign,
        Rounding::Zero => false,
    };
    let overflow_to_inf = match mode {
        Rounding::Nearest => true,
        Rounding::PlusInf => !sign,
        Rounding::MinusInf => sign,
        Rounding::Zero => false,
    };
    if up {
        int_mant += 1;
        if int_mant == 1 << f {
            biased = 1;
        }
        if int_mant == 2 << f {
            biased += 1;
            int_mant >>= 1;
        }
    }
    let frac = (int_mant as u32) & ((1 << f) - 1);
    let max_biased = (1i32 << fmt.exp_bits) - 1;
    let ahp = fmt.half && *fpscr & fpscr::AHP != 0;
    let mut inexact = inexact;
    let result = if !ahp {
        if biased >= max_biased {
            *fpscr |= fpscr::OFC;
            inexact = true;
            if overflow_to_inf {
                sign_bit | (max_biased as u32) << fmt.frac_bits
            } else {
                sign_bit | ((max_biased - 1) as u32) << fmt.frac_bits | ((1 << f) - 1)
            }
        } else {
            sign_bit | (biased as u32) << fmt.frac_bits | frac
        }
    } else if biased > max_biased {
        *fpscr |= fpscr::IOC;
        inexact = false;
        sign_bit | 0x7FFF
    } else {
        sign_bit | (biased as u32) << fmt.frac_bits | frac
    };
    if inexact {
        *fpscr |= fpscr::IXC;
    }
    result
}

/// Normalises a non-zero mantissa so its top bit is bit 60.
fn normalise(mant: u128, exp: i32) -> (u128, i32) {
    let msb = 127 - mant.leading_zeros() as i32;
    let shift = 60 - msb;
    if shift >= 0 {
        (mant << shift, exp - shift)
    } else {
        (mant >> -shift, exp - shift)
    }
}

/// The exact signed sum of two non-zero finite values (mantissas below 2^60), as a sign,
/// a magnitude with exponent, and a sticky bit when the smaller one only nudges it.
fn sum_exact(a: (bool, u128, i32), b: (bool, u128, i32)) -> (bool, u128, i32, bool) {
    let (sa, ma, ea) = a;
    let (sb, mb, eb) = b;
    let (ma, ea) = normalise(ma, ea);
    let (mb, eb) = normalise(mb, eb);
    let ((sa, ma, ea), (sb, mb, eb)) = if ea >= eb {
        ((sa, ma, ea), (sb, mb, eb))
    } else {
        ((sb, mb, eb), (sa, ma, ea))
    };
    let d = (ea - eb) as u32;
    if d <= 64 {
        let big = ma << d;
        if sa == sb {
            (sa, big + mb, eb, false)
        } else if big >= mb {
            (sa, big - mb, eb, false)
        } else {
            (sb, mb - big, eb, false)
        }
    } else {
        // b is below a quarter of a unit of a's 63-bit mantissa.
        let big = ma << 2;
        if sa == sb {
            (sa, big, ea - 2, true)
        } else {
            (sa, big - 1, ea - 2, true)
        }
    }
}

/// Rounds an exact sum, or gives the signed zero of an exact cancellation.
fn round_sum(sum: (bool, u128, i32, bool), mode: Rounding, fpscr: &mut u32) -> u32 {
    let (sign, mant, exp, sticky) = sum;
    if mant == 0 && !sticky {
        return zero(mode == Rounding::MinusInf);
    }
    round(SINGLE, sign, mant, exp, sticky, mode, fpscr)
}

/// `FPAdd` (and `FPSub` as an add of the negated operand).
fn add_exact_op(a: u32, b: u32, fpscr: &mut u32) -> u32 {
    let mode = Rounding::of(*fpscr);
    let x = unpack(a, fpscr);
    let y = unpack(b, fpscr);
    if let Some(r) = process_nans(&[&x, &y], fpscr) {
        return r;
    }
    match (x.kind, y.kind) {
        (Kind::Inf, Kind::Inf) if x.sign != y.sign => invalid(fpscr),
        (Kind::Inf, _) => inf(x.sign),
        (_, Kind::Inf) => inf(y.sign),
        (Kind::Zero, Kind::Zero) if x.sign == y.sign => zero(x.sign),
        (Kind::Zero, Kind::Zero) => zero(mode == Rounding::MinusInf),
        (Kind::Zero, _) => round(SINGLE, y.sign, y.mant, y.exp, false, mode, fpscr),
        (_, Kind::Zero) => round(SINGLE, x.sign, x.mant, x.exp, false, mode, fpscr),
        _ => round_sum(
            sum_exact((x.sign, x.mant, x.exp), (y.sign, y.mant, y.exp)),
            mode,
            fpscr,
        ),
    }
}

/// `FPSub`.
pub(crate) fn sub(a: u32, b: u32, fpscr: &mut u32) -> u32 {
    if let Some(r) = fast::add(a, b ^ 0x8000_0000, fpscr) {
        return r;
    }
    let x = unpack(a, fpscr);
    let y = unpack(b, fpscr);
    // NaN operands keep their own sign: process them before negating.
    if let Some(r) = process_nans(&[&x, &y], fpscr) {
        return r;
    }
    add(a, b ^ 0x8000_0000, fpscr)
}

/// `FPMul`.
fn mul_exact(a: u32, b: u32, fpscr: &mut u32) -> u32 {
    let mode = Rounding::of(*fpscr);
    let x = unpack(a, fpscr);
    let y = unpack(b, fpscr);
    if let Some(r) = process_nans(&[&x, &y], fpscr) {
        return r;
    }
    let sign = x.sign != y.sign;
    match (x.kind, y.kind) {
        (Kind::Inf, Kind::Zero) | (Kind::Zero, Kind::Inf) => invalid(fpscr),
        (Kind::Inf, _) | (_, Kind::Inf) => inf(sign),
        (Kind::Zero, _) | (_, Kind::Zero) => zero(sign),
        _ => round(
            SINGLE,
            sign,
            x.mant * y.mant,
            x.exp + y.exp,
            false,
            mode,
            fpscr,
        ),
    }
}

/// `FPMulAdd`: `addend + a × b` with one rounding.
pub(crate) fn mul_add(addend: u32, a: u32, b: u32, fpscr: &mut u32) -> u32 {
    let mode = Rounding::of(*fpscr);
    let z = unpack(addend, fpscr);
    let x = unpack(a, fpscr);
    let y = unpack(b, fpscr);
    let inf_times_zero = matches!(
        (x.kind, y.kind),
        (Kind::Inf, Kind::Zero) | (Kind::Zero, Kind::Inf)
    );
    if let Some(r) = process_nans(&[&z, &x, &y], fpscr) {
        if z.kind == Kind::QNaN && inf_times_zero {
            return invalid(fpscr);
        }
        return r;
    }
    let sign_p = x.sign != y.sign;
    let inf_p = x.kind == Kind::Inf || y.kind == Kind::Inf;
    let zero_p = x.kind == Kind::Zero || y.kind == Kind::Zero;
    if inf_times_zero || (z.kind == Kind::Inf && inf_p && z.sign != sign_p) {
        return invalid(fpscr);
    }
    if z.kind == Kind::Inf {
        return inf(z.sign);
    }
    if inf_p {
        return inf(sign_p);
    }
    if z.kind == Kind::Zero && zero_p {
        return if z.sign == sign_p {
            zero(z.sign)
        } else {
            zero(mode == Rounding::MinusInf)
        };
    }
    if zero_p {
        return round(SINGLE, z.sign, z.mant, z.exp, false, mode, fpscr);
    }
    let product = (sign_p, x.mant * y.mant, x.exp + y.exp);
    if z.kind == Kind::Zero {
        return round(SINGLE, product.0, product.1, product.2, false, mode, fpscr);
    }
    round_sum(sum_exact((z.sign, z.mant, z.exp), product), mode, fpscr)
}

/// `FPDiv`.
fn div_exact(a: u32, b: u32, fpscr: &mut u32) -> u32 {
    let mode = Rounding::of(*fpscr);
    let x = unpack(a, fpscr);
    let y = unpack(b, fpscr);
    if let Some(r) = process_nans(&[&x, &y], fpscr) {
        return r;
    }
    let sign = x.sign != y.sign;
    match (x.kind, y.kind) {
        (Kind::Inf, Kind::Inf) | (Kind::Zero, Kind::Zero) => invalid(fpscr),
        (Kind::Inf, _) => inf(sign),
        (_, Kind::Zero) => {
            *fpscr |= fpscr::DZC;
            inf(sign)
        }
        (Kind::Zero, _) | (_, Kind::Inf) => zero(sign),
        _ => {
            let num = x.mant << 100;
            let q = num / y.mant;
            let sticky = !num.is_multiple_of(y.mant);
            round(SINGLE, sign, q, x.exp - y.exp - 100, sticky, mode, fpscr)
        }
    }
}

/// `FPSqrt`.
fn sqrt_exact(a: u32, fpscr: &mut u32) -> u32 {
    let mode = Rounding::of(*fpscr);
    let x = unpack(a, fpscr);
    if x.is_nan() {
        return process_nan(&x, fpscr);
    }
    match x.kind {
        Kind::Zero => zero(x.sign),
        _ if x.sign => invalid(fpscr),
        Kind::Inf => inf(false),
        _ => {
            let (mut m, mut e) = (x.mant, x.exp);
            if e & 1 != 0 {
                m <<= 1;
                e -= 1;
            }
            let n = m << 52;
            let r = isqrt(n);
            round(SINGLE, false, r, (e - 52) / 2, r * r != n, mode, fpscr)
        }
    }
}

/// ⌊√n⌋ for n below 2^80.
fn isqrt(n: u128) -> u128 {
    let mut r = (n as f64).sqrt() as u128;
    while r * r > n {
        r -= 1;
    }
    while (r + 1) * (r + 1) <= n {
        r += 1;
    }
    r
}

/// `FPAdd`.
pub(crate) fn add(a: u32, b: u32, fpscr: &mut u32) -> u32 {
    fast::add(a, b, fpscr).unwrap_or_else(|| add_exact_op(a, b, fpscr))
}

/// `FPMul`.
pub(crate) fn mul(a: u32, b: u32, fpscr: &mut u32) -> u32 {
    fast::mul(a, b, fpscr).unwrap_or_else(|| mul_exact(a, b, fpscr))
}

/// `FPDiv`.
pub(crate) fn div(a: u32, b: u32, fpscr: &mut u32) -> u32 {
    fast::div(a, b, fpscr).unwrap_or_else(|| div_exact(a, b, fpscr))
}

/// `FPSqrt`.
pub(crate) fn sqrt(a: u32, fpscr: &mut u32) -> u32 {
    fast::sqrt(a, fpscr).unwrap_or_else(|| sqrt_exact(a, fpscr))
}

/// The common case on the host's IEEE arithmetic: round to nearest, operands and result
/// normal (or zero), where IEEE 754 and the ARM pseudocode give the same bits. The only
/// flag such an operation can raise is Inexact, found by checking the result exactly.
/// Everything else (other rounding modes, denormals, infinities, NaNs, overflow, results
/// near the underflow threshold) returns `None` for the exact path.
mod fast {
    use super::fpscr;

    const MIN_NORMAL: f32 = f32::MIN_POSITIVE;

    /// Round to nearest.
    #[inline(always)]
    fn nearest(f: u32) -> bool {
        f >> fpscr::RMODE_SHIFT & 3 == 0
    }

    /// A normal number or a zero (exponent neither all zeros with a fraction nor all ones).
    #[inline(always)]
    fn plain(bits: u32) -> bool {
        let e = bits >> 23 & 0xFF;
        e != 0xFF && (e != 0 || bits & 0x7F_FFFF == 0)
    }

    /// A normal number.
    #[inline(always)]
    fn normal(bits: u32) -> bool {
        let e = bits >> 23 & 0xFF;
        e != 0xFF && e != 0
    }

    /// A result that is zero or safely above the underflow threshold and finite.
    #[inline(always)]
    fn result_ok(r: f32) -> bool {
        r == 0.0 || (r.abs() > MIN_NORMAL && r.is_finite())
    }

    #[inline(always)]
    fn finish(r: f32, exact: bool, f: &mut u32) -> u32 {
        if !exact {
            *f |= fpscr::IXC;
        }
        r.to_bits()
    }

    #[inline(always)]
    pub fn add(a: u32, b: u32, f: &mut u32) -> Option<u32> {
        if !(nearest(*f) && plain(a) && plain(b)) {
            return None;
        }
        let (x, y) = (f32::from_bits(a), f32::from_bits(b));
        let r = x + y;
        if !result_ok(r) {
            return None;
        }
        // TwoSum in double: s + e is the exact sum of the two singles.
        let (xd, yd) = (f64::from(x), f64::from(y));
        let s = xd + yd;
        let bb = s - xd;
        let e = (xd - (s - bb)) + (yd - bb);
        Some(finish(r, e == 0.0 && s == f64::from(r), f))
    }

    #[inline(always)]
    pub fn mul(a: u32, b: u32, f: &mut u32) -> Option<u32> {
        if !(nearest(*f) && plain(a) && plain(b)) {
            return None;
        }
        // The product of two singles is exact in double; rounding it once is IEEE's and
        // ARM's result. A zero product only comes from a zero operand.
        let p = f64::from(f32::from_bits(a)) * f64::from(f32::from_bits(b));
        let r = p as f32;
        if !result_ok(r) || (r == 0.0) != (p == 0.0) {
            return None;
        }
        Some(finish(r, f64::from(r) == p, f))
    }

    #[inline(always)]
    pub fn div(a: u32, b: u32, f: &mut u32) -> Option<u32> {
        if !(nearest(*f) && plain(a) && normal(b)) {
            return None;
        }
        let (x, y) = (f32::from_bits(a), f32::from_bits(b));
        let r = x / y;
        if !result_ok(r) || (r == 0.0 && x != 0.0) {
            return None;
        }
        // Exact when r × y (exact in double) gives x back.
        Some(finish(r, f64::from(r) * f64::from(y) == f64::from(x), f))
    }

    #[inline(always)]
    pub fn sqrt(a: u32, f: &mut u32) -> Option<u32> {
        if !(nearest(*f) && normal(a) && a >> 31 == 0) {
            return None;
        }
        let x = f32::from_bits(a);
        let r = x.sqrt();
        let rd = f64::from(r);
        Some(finish(r, rd * rd == f64::from(x), f))
    }

    /// `FPCompare` of two plain operands (no flags possible).
    #[inline(always)]
    pub fn compare(a: u32, b: u32) -> Option<u32> {
        if !(plain(a) && plain(b)) {
            return None;
        }
        let (x, y) = (f32::from_bits(a), f32::from_bits(b));
        Some(if x == y {
            0b0110 << 28
        } else if x < y {
            0b1000 << 28
        } else {
            0b0010 << 28
        })
    }
}

/// `FPCompare`: the NZCV flags (bits 31:28); `signal_qnan` for VCMPE.
pub(crate) fn compare(a: u32, b: u32, signal_qnan: bool, fpscr: &mut u32) -> u32 {
    if let Some(r) = fast::compare(a, b) {
        return r;
    }
    let x = unpack(a, fpscr);
    let y = unpack(b, fpscr);
    if x.is_nan() || y.is_nan() {
        if signal_qnan || x.kind == Kind::SNaN || y.kind == Kind::SNaN {
            *fpscr |= fpscr::IOC;
        }
        return 0b0011 << 28;
    }
    let (vx, vy) = (value_f64(&x), value_f64(&y));
    if vx == vy {
        0b0110 << 28
    } else if vx < vy {
        0b1000 << 28
    } else {
        0b0010 << 28
    }
}

/// An unpacked non-NaN operand as an (exact) double, for ordering.
fn value_f64(v: &Val) -> f64 {
    let magnitude = match v.kind {
        Kind::Zero => 0.0,
        Kind::Inf => f64::INFINITY,
        _ => v.mant as f64 * 2f64.powi(v.exp),
    };
    if v.sign { -magnitude } else { magnitude }
}

/// `FPToFixed`: `a × 2^frac` to a `size`-bit integer (sign- or zero-extended to 32 bits),
/// rounding toward zero or in FPSCR's mode, saturating with Invalid.
pub(crate) fn to_fixed(
    a: u32,
    frac: u32,
    unsigned: bool,
    size: u32,
    toward_zero: bool,
    fpscr: &mut u32,
) -> u32 {
    let mode = if toward_zero {
        Rounding::Zero
    } else {
        Rounding::of(*fpscr)
    };
    let x = unpack(a, fpscr);
    let (q, gt_half, eq_half, inexact) = match x.kind {
        Kind::QNaN | Kind::SNaN => {
            *fpscr |= fpscr::IOC;
            return 0;
        }
        Kind::Zero => (0u128, false, false, false),
        Kind::Inf => (u128::MAX >> 1, false, false, false),
        Kind::Finite => {
            let e = x.exp + frac as i32;
            if e >= 0 {
                (
                    if e > 64 { u128::MAX >> 1 } else { x.mant << e },
                    false,
                    false,
                    false,
                )
            } else {
                let sh = (-e) as u32;
                if sh >= 100 {
                    (0, false, false, true)
                } else {
                    let rem = x.mant & ((1u128 << sh) - 1);
                    let half = 1u128 << (sh - 1);
                    (x.mant >> sh, rem > half, rem == half, rem != 0)
                }
            }
        }
    };
    let up = match mode {
        Rounding::Nearest => gt_half || (eq_half && q & 1 != 0),
        Rounding::PlusInf => inexact && !x.sign,
        Rounding::MinusInf => inexact && x.sign,
        Rounding::Zero => false,
    };
    let magnitude = q.saturating_add(u128::from(up)).min(1 << 100) as i128;
    let value = if x.sign { -magnitude } else { magnitude };
    let (lo, hi): (i128, i128) = if unsigned {
        (0, (1i128 << size) - 1)
    } else {
        (-(1i128 << (size - 1)), (1i128 << (size - 1)) - 1)
    };
    let clamped = value.clamp(lo, hi);
    if clamped != value {
        *fpscr |= fpscr::IOC;
    } else if inexact {
        *fpscr |= fpscr::IXC;
    }
    let bits = clamped as u32;
    if size == 16 {
        if unsigned {
            bits & 0xFFFF
        } else {
            bits as u16 as i16 as i32 as u32
        }
    } else {
        bits
    }
}

/// `FixedToFP`: a `size`-bit integer with `frac` fraction bits to single precision,
/// rounding to nearest (`nearest`, the fixed-point VCVT) or in FPSCR's mode (the integer
/// VCVT).
pub(crate) fn from_fixed(
    v: u32,
    frac: u32,
    unsigned: bool,
    size: u32,
    nearest: bool,
    fpscr: &mut u32,
) -> u32 {
    let mode = if nearest {
        Rounding::Nearest
    } else {
        Rounding::of(*fpscr)
    };
    let value: i64 = match (size, unsigned) {
        (16, true) => i64::from(v as u16),
        (16, false) => i64::from(v as u16 as i16),
        (_, true) => i64::from(v),
        (_, false) => i64::from(v as i32),
    };
    if value == 0 {
        return 0;
    }
    round(
        SINGLE,
        value < 0,
        u128::from(value.unsigned_abs()),
        -(frac as i32),
        false,
        mode,
        fpscr,
    )
}

/// Single to half precision (VCVTB/VCVTT to half), honouring AHP, DN and the rounding
/// mode.
pub(crate) fn single_to_half(a: u32, fpscr: &mut u32) -> u32 {
    let mode = Rounding::of(*fpscr);
    let ahp = *fpscr & fpscr::AHP != 0;
    let x = unpack(a, fpscr);
    let sign = u32::from(x.sign) << 15;
    match x.kind {
        Kind::QNaN | Kind::SNaN => {
            let r = if ahp {
                // No NaN in the alternative format: a zero of the NaN's sign.
                sign
            } else if *fpscr & fpscr::DN != 0 {
                DEFAULT_NAN_HALF
            } else {
                sign | 0x7E00 | (a >> 13 & 0x1FF)
            };
            if ahp || x.kind == Kind::SNaN {
                *fpscr |= fpscr::IOC;
            }
            r
        }
        Kind::Inf => {
            if ahp {
                *fpscr |= fpscr::IOC;
                sign | 0x7FFF
            } else {
                sign | 0x7C00
            }
        }
        Kind::Zero => sign,
        Kind::Finite => round(HALF, x.sign, x.mant, x.exp, false, mode, fpscr),
    }
}

/// Half to single precision (VCVTB/VCVTT from half): exact, AHP and DN honoured.
pub(crate) fn half_to_single(h: u32, fpscr: &mut u32) -> u32 {
    let ahp = *fpscr & fpscr::AHP != 0;
    let sign = h >> 15 & 1 != 0;
    let e = (h >> 10 & 0x1F) as i32;
    let f = h & 0x3FF;
    if e == 0x1F && !ahp {
        if f == 0 {
            return inf(sign);
        }
        let snan = f & 0x200 == 0;
        if snan {
            *fpscr |= fpscr::IOC;
        }
        if *fpscr & fpscr::DN != 0 {
            return DEFAULT_NAN;
        }
        return u32::from(sign) << 31 | 0x7FC0_0000 | (f & 0x1FF) << 13;
    }
    let (mant, exp) = if e == 0 {
        if f == 0 {
            return zero(sign);
        }
        (f, -24)
    } else {
        (f | 0x400, e - 25)
    };
    // Every half-precision value is exact in single precision.
    round(
        SINGLE,
        sign,
        u128::from(mant),
        exp,
        false,
        Rounding::Nearest,
        fpscr,
    )
}

#[cfg(test)]
mod tests;
