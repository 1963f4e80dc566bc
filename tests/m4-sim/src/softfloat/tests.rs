//! The soft-float against the ARM ARM's rules at the edges, and its host fast path against
//! the exact path everywhere.

use super::*;

const FZ: u32 = fpscr::FZ;
const DN: u32 = fpscr::DN;
const RP: u32 = 1 << 22;
const RM: u32 = 2 << 22;
const RZ: u32 = 3 << 22;

fn f(v: f32) -> u32 {
    v.to_bits()
}

/// Runs `op` with FPSCR = `mode` and returns the result and the flags it raised.
fn with(mode: u32, op: impl Fn(&mut u32) -> u32) -> (u32, u32) {
    let mut fpscr = mode;
    let r = op(&mut fpscr);
    (r, fpscr & !mode)
}

#[test]
fn rounding_modes_on_a_tie_and_on_a_negative() {
    // 1 + 2^-24 is halfway between 1 and the next single.
    let a = f(1.0);
    let b = f(2f32.powi(-24));
    assert_eq!(with(0, |m| add(a, b, m)), (f(1.0), fpscr::IXC));
    assert_eq!(with(RP, |m| add(a, b, m)).0, 0x3F80_0001);
    assert_eq!(with(RM, |m| add(a, b, m)).0, f(1.0));
    assert_eq!(with(RZ, |m| add(a, b, m)).0, f(1.0));
    // Ties go to the even neighbour: (1 + 2^-23) + 2^-24 rounds up.
    assert_eq!(with(0, |m| add(0x3F80_0001, b, m)).0, 0x3F80_0002);
    // Negative values round away from zero toward minus infinity.
    assert_eq!(
        with(RM, |m| add(f(-1.0), b ^ 0x8000_0000, m)).0,
        0xBF80_0001
    );
    assert_eq!(with(RP, |m| add(f(-1.0), b ^ 0x8000_0000, m)).0, f(-1.0));
}

#[test]
fn overflow_depends_on_the_mode() {
    let max = f(f32::MAX);
    for (mode, want) in [
        (0, 0x7F80_0000),
        (RP, 0x7F80_0000),
        (RM, 0x7F7F_FFFF),
        (RZ, 0x7F7F_FFFF),
    ] {
        assert_eq!(
            with(mode, |m| mul(max, f(2.0), m)),
            (want, fpscr::OFC | fpscr::IXC)
        );
    }
    assert_eq!(with(RP, |m| mul(max, f(-2.0), m)).0, 0xFF7F_FFFF);
}

#[test]
fn underflow_is_tiny_and_inexact_before_rounding() {
    let tiny = f(f32::MIN_POSITIVE);
    // Exactly representable denormal: no underflow flag.
    assert_eq!(with(0, |m| mul(tiny, f(0.5), m)), (0x0040_0000, 0));
    // Inexact denormal: UFC and IXC.
    let (r, flags) = with(0, |m| mul(tiny, f(1.0 / 3.0), m));
    assert_eq!(r, 0x002A_AAAB);
    assert_eq!(flags, fpscr::UFC | fpscr::IXC);
    // A result that rounds up to the smallest normal is still tiny before rounding:
    // (2^23 - 1)·2^-149 × (1 + 2^-23) = (2^23 - 2^-23)·2^-149.
    let (r, flags) = with(0, |m| mul(0x007F_FFFF, 0x3F80_0001, m));
    assert_eq!(r, tiny);
    assert_eq!(flags, fpscr::UFC | fpscr::IXC);
    // Flush-to-zero flushes a tiny result to zero with UFC only, keeping the sign.
    assert_eq!(
        with(FZ, |m| mul(tiny, f(-0.5), m)),
        (0x8000_0000, fpscr::UFC)
    );
    // ... and denormal inputs with IDC.
    assert_eq!(with(FZ, |m| add(1, f(1.0), m)), (f(1.0), fpscr::IDC));
}

#[test]
fn nan_propagation() {
    let qnan = 0x7FC0_1234;
    let snan = 0x7F80_5678;
    // A signalling NaN wins over a quiet one, quietened, with Invalid.
    assert_eq!(with(0, |m| add(qnan, snan, m)), (0x7FC0_5678, fpscr::IOC));
    // Two quiet NaNs: the first operand's.
    assert_eq!(with(0, |m| mul(qnan, 0xFFC0_0001, m)), (qnan, 0));
    // Default NaN mode replaces any NaN result.
    assert_eq!(with(DN, |m| div(qnan, f(1.0), m)), (DEFAULT_NAN, 0));
    // Invalid operations give the default NaN.
    assert_eq!(
        with(0, |m| mul(f(0.0), f(f32::INFINITY), m)),
        (DEFAULT_NAN, fpscr::IOC)
    );
    assert_eq!(
        with(0, |m| add(f(f32::INFINITY), f(f32::NEG_INFINITY), m)),
        (DEFAULT_NAN, fpscr::IOC)
    );
    assert_eq!(with(0, |m| sqrt(f(-4.0), m)), (DEFAULT_NAN, fpscr::IOC));
    // FPSub negates after NaN processing: a NaN second operand keeps its sign.
    assert_eq!(with(0, |m| sub(f(1.0), qnan, m)).0, qnan);
    // FMA: a quiet NaN addend with ∞ × 0 is still Invalid.
    assert_eq!(
        with(0, |m| mul_add(qnan, f(0.0), f(f32::INFINITY), m)),
        (DEFAULT_NAN, fpscr::IOC)
    );
    assert_eq!(with(0, |m| mul_add(qnan, f(2.0), f(3.0), m)), (qnan, 0));
}

#[test]
fn signed_zeros() {
    assert_eq!(with(0, |m| add(f(1.0), f(-1.0), m)).0, 0);
    assert_eq!(with(RM, |m| add(f(1.0), f(-1.0), m)).0, 0x8000_0000);
    assert_eq!(with(0, |m| add(f(-0.0), f(-0.0), m)).0, 0x8000_0000);
    assert_eq!(with(0, |m| add(f(-0.0), f(0.0), m)).0, 0);
    assert_eq!(with(0, |m| sqrt(f(-0.0), m)), (0x8000_0000, 0));
    assert_eq!(
        with(0, |m| div(f(-1.0), f(f32::INFINITY), m)).0,
        0x8000_0000
    );
    assert_eq!(with(0, |m| mul_add(f(0.0), f(-0.0), f(1.0), m)).0, 0);
    assert_eq!(
        with(0, |m| mul_add(f(-0.0), f(-0.0), f(1.0), m)).0,
        0x8000_0000
    );
    assert_eq!(
        with(0, |m| div(f(1.0), f(-0.0), m)),
        (0xFF80_0000, fpscr::DZC)
    );
}

#[test]
fn compare_orders_and_flags() {
    let nzcv = |a, b, e| with(0, |m| compare(a, b, e, m));
    assert_eq!(nzcv(f(1.0), f(2.0), false), (0x8000_0000, 0));
    assert_eq!(nzcv(f(-0.0), f(0.0), false), (0x6000_0000, 0));
    assert_eq!(nzcv(f(f32::INFINITY), f(f32::MAX), false), (0x2000_0000, 0));
    assert_eq!(nzcv(0x7FC0_0000, f(0.0), false), (0x3000_0000, 0));
    assert_eq!(nzcv(0x7FC0_0000, f(0.0), true), (0x3000_0000, fpscr::IOC));
    assert_eq!(nzcv(0x7F80_0001, f(0.0), false), (0x3000_0000, fpscr::IOC));
    // FZ: a denormal equals zero.
    assert_eq!(
        with(FZ, |m| compare(1, 0, false, m)),
        (0x6000_0000, fpscr::IDC)
    );
}

#[test]
fn fixed_point_conversions() {
    // 16-bit signed with 8 fraction bits, rounding toward zero.
    assert_eq!(
        with(0, |m| to_fixed(f(-1.75), 8, false, 16, true, m)),
        ((-448i32) as u32, 0)
    );
    assert_eq!(
        with(0, |m| to_fixed(f(200.0), 8, false, 16, true, m)),
        (0x7FFF, fpscr::IOC)
    );
    assert_eq!(
        with(0, |m| to_fixed(f(1.0 / 3.0), 8, true, 16, true, m)),
        (85, fpscr::IXC)
    );
    assert_eq!(
        with(0, |m| from_fixed(0xFFFF, 16, false, 16, true, m)).0,
        f(-1.0 / 65536.0)
    );
    // Fixed point converts to nearest even under another FPSCR mode; integers do not.
    let fixed = with(RZ, |m| from_fixed(0x0100_0003, 1, false, 32, true, m));
    assert_eq!(fixed.0, 0x4B00_0002);
    let integer = with(RZ, |m| from_fixed(0x0100_0003, 0, false, 32, false, m));
    assert_eq!(integer.0, 0x4B80_0001);
    assert_eq!(
        with(0, |m| from_fixed(0x8000_0000, 31, true, 32, true, m)).0,
        f(1.0)
    );
}

#[test]
fn half_precision() {
    assert_eq!(
        with(0, |m| single_to_half(f(65520.0), m)),
        (0x7C00, fpscr::OFC | fpscr::IXC)
    );
    assert_eq!(
        with(0, |m| single_to_half(f(65519.0), m)),
        (0x7BFF, fpscr::IXC)
    );
    assert_eq!(with(0, |m| single_to_half(f(2f32.powi(-24)), m)), (1, 0));
    assert_eq!(
        with(0, |m| single_to_half(f(2f32.powi(-26)), m)),
        (0, fpscr::UFC | fpscr::IXC)
    );
    assert_eq!(
        with(0, |m| single_to_half(0x7F80_0001, m)),
        (0x7E00, fpscr::IOC)
    );
    assert_eq!(
        with(fpscr::AHP, |m| single_to_half(0xFFC0_0000, m)),
        (0x8000, fpscr::IOC)
    );
    assert_eq!(
        with(0, |m| half_to_single(0x0001, m)),
        (f(2f32.powi(-24)), 0)
    );
    assert_eq!(
        with(0, |m| half_to_single(0xFC00, m)).0,
        f(f32::NEG_INFINITY)
    );
    assert_eq!(
        with(0, |m| half_to_single(0x7D00, m)),
        (0x7FE0_0000, fpscr::IOC)
    );
}

/// A small deterministic generator (SplitMix64) for the randomized comparisons.
struct Gen(u64);

impl Gen {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Operands biased toward the interesting: nearby exponents, edges, specials.
    fn operand(&mut self, near: u32) -> u32 {
        let r = self.next();
        match r % 8 {
            0 => {
                [
                    0,
                    0x8000_0000,
                    1,
                    0x007F_FFFF,
                    0x0080_0000,
                    0x7F7F_FFFF,
                    0x7F80_0000,
                    0x7FC0_0000,
                    0x7F80_0001,
                    0x3F80_0000,
                ][(r >> 8) as usize % 10]
                    ^ ((r >> 20) as u32 & 0x8000_0000)
            }
            1 | 2 => near ^ ((r >> 8) as u32 & 0x807F_FFFF) ^ (((r >> 40) as u32 % 5) << 23),
            _ => (r >> 16) as u32,
        }
    }
}

#[test]
fn the_fast_path_agrees_with_the_exact_path() {
    let mut g = Gen(7);
    let modes = [0, FZ, DN, FZ | DN, RP, RM, RZ];
    for i in 0..200_000u32 {
        let a = g.operand(0x3F80_0000);
        let b = g.operand(a);
        let mode = modes[i as usize % modes.len()] | (i & fpscr::IXC);
        let fast_or_exact = [
            with(mode, |m| add(a, b, m)),
            with(mode, |m| mul(a, b, m)),
            with(mode, |m| div(a, b, m)),
            with(mode, |m| sqrt(a, m)),
            with(mode, |m| compare(a, b, false, m)),
        ];
        let exact = [
            with(mode, |m| add_exact_op(a, b, m)),
            with(mode, |m| mul_exact(a, b, m)),
            with(mode, |m| div_exact(a, b, m)),
            with(mode, |m| sqrt_exact(a, m)),
            {
                // The exact compare: without the fast path's shortcut.
                let mut m = mode;
                let x = unpack(a, &mut m);
                let y = unpack(b, &mut m);
                let r = if x.is_nan() || y.is_nan() {
                    if x.kind == Kind::SNaN || y.kind == Kind::SNaN {
                        m |= fpscr::IOC;
                    }
                    0x3000_0000
                } else if value_f64(&x) == value_f64(&y) {
                    0x6000_0000
                } else if value_f64(&x) < value_f64(&y) {
                    0x8000_0000
                } else {
                    0x2000_0000
                };
                (r, m & !mode)
            },
        ];
        assert_eq!(
            fast_or_exact, exact,
            "a {a:#010x} b {b:#010x} mode {mode:#x}"
        );
    }
}

#[test]
fn the_exact_path_agrees_with_ieee_hardware_where_arm_and_ieee_agree() {
    // Round to nearest, no FZ/DN, non-NaN results: IEEE 754 and the ARM pseudocode give
    // the same bits (NaN payloads and flags aside).
    let mut g = Gen(11);
    for _ in 0..200_000 {
        let a = g.operand(0x3F80_0000);
        let b = g.operand(a);
        let c = g.operand(b);
        let (x, y, z) = (f32::from_bits(a), f32::from_bits(b), f32::from_bits(c));
        let checks = [
            (with(0, |m| add_exact_op(a, b, m)).0, x + y),
            (with(0, |m| mul_exact(a, b, m)).0, x * y),
            (with(0, |m| div_exact(a, b, m)).0, x / y),
            (with(0, |m| sqrt_exact(a, m)).0, x.sqrt()),
            (with(0, |m| mul_add(c, a, b, m)).0, x.mul_add(y, z)),
        ];
        for (ours, ieee) in checks {
            if !ieee.is_nan() {
                assert_eq!(ours, ieee.to_bits(), "a {a:#010x} b {b:#010x} c {c:#010x}");
            }
        }
    }
}
