//! Decimal text of `f32` values for a microcontroller's console: the shortest text that reads
//! back as the same value ([`Shortest`], what `{}` prints), a fixed number of decimals for
//! status lines ([`Fixed`]), and the reading of typed numbers ([`parse`]) — each exact, in
//! ≈ 3 KB of integer arithmetic instead of core's float formatting and parsing
//! (Grisu/Dragon and the Eisel-Lemire tables, ≈ 25 KB of flash on a Cortex-M4; TauLink
//! issue 33). `no_std`, no heap, no tables.
//!
//! ```
//! use float_text::{Fixed, Shortest, parse};
//!
//! assert_eq!(format!("{}", Shortest(0.004)), "0.004");
//! assert_eq!(format!("{}", Shortest(1e-7)), format!("{}", 1e-7f32)); // "0.0000001"
//! assert_eq!(format!("{}", Fixed(2.345, 2)), "2.35"); // 2.345f32 is 2.34500003…
//! assert_eq!(parse("0.004"), Some(0.004));
//! assert_eq!(parse("1e-3"), Some(0.001));
//! assert_eq!(parse("0x10"), None);
//! ```
//!
//! Exactness rests on one small unsigned big integer (`Big`): reading computes the 25
//! leading bits of the typed decimal's exact quotient and rounds half to even, as IEEE 754
//! and `str::parse` do; the shortest text is Steele & White's free-format digit generation
//! (Burger & Dybvig's formulation) over the exact interval of reals that read back as the
//! value, which picks, among the shortest such texts, the one closest to the value — the
//! same digits `core` prints. Both are tested against `core` on the host over the whole
//! `f32` range (`src/tests.rs`).
//!
//! Reading accepts what `str::parse::<f32>` accepts (`[+-]`, digits with an optional point,
//! an optional exponent, `inf`, `infinity`, `nan` in any case) with at most
//! [`MAX_DIGITS`] significant digits; longer numbers are refused rather than rounded twice.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use core::cmp::Ordering;
use core::fmt;

/// Most significant digits a typed number may have (they must fit a `u64`); `f32` needs 9
/// to name any value.
pub const MAX_DIGITS: u32 = 19;

/// Limbs of [`Big`]: the largest number either direction builds is below 2²⁴⁰ (reading
/// 1e-64 scaled by 2¹⁵⁰·2²⁷ for its quotient bits); 256 bits.
const LIMBS: usize = 8;

/// An unsigned integer of up to `32 · LIMBS` bits, little-endian limbs, `len` of them in
/// use. An operation that would need more sets `overflow` (never expected: the sizes above
/// bound every input), and the caller refuses the result.
#[derive(Clone, Copy)]
struct Big {
    limbs: [u32; LIMBS],
    len: usize,
    overflow: bool,
}

impl Big {
    fn from_u64(v: u64) -> Self {
        let mut b = Self {
            limbs: [0; LIMBS],
            len: 2,
            overflow: false,
        };
        b.limbs[0] = v as u32;
        b.limbs[1] = (v >> 32) as u32;
        b.trim();
        b
    }

    fn used(&self) -> &[u32] {
        self.limbs.get(..self.len).unwrap_or(&[])
    }

    fn trim(&mut self) {
        while self.len > 0 && self.limbs.get(self.len - 1) == Some(&0) {
            self.len -= 1;
        }
    }

    fn push(&mut self, limb: u32) {
        match self.limbs.get_mut(self.len) {
            Some(slot) => {
                *slot = limb;
                self.len += 1;
            }
            None => self.overflow = true,
        }
    }

    fn is_zero(&self) -> bool {
        self.len == 0
    }

    fn bit_len(&self) -> u32 {
        match self.used().last() {
            Some(top) => 32 * self.len as u32 - top.leading_zeros(),
            None => 0,
        }
    }

    #[inline(never)]
    fn mul_small(&mut self, m: u32) {
        let mut carry = 0u64;
        for limb in self.limbs.iter_mut().take(self.len) {
            let p = u64::from(*limb) * u64::from(m) + carry;
            *limb = p as u32;
            carry = p >> 32;
        }
        if carry != 0 {
            self.push(carry as u32);
        }
    }

    fn mul_pow10(&mut self, mut k: u32) {
        while k >= 9 {
            self.mul_small(1_000_000_000);
            k -= 9;
        }
        self.mul_small(10u32.pow(k));
    }

    #[inline(never)]
    fn shl(&mut self, bits: u32) {
        if self.is_zero() {
            return;
        }
        for _ in 0..bits / 32 {
            self.push(0);
            self.limbs.rotate_right(1);
        }
        let s = bits % 32;
        if s != 0 {
            let mut carry = 0u32;
            for limb in self.limbs.iter_mut().take(self.len) {
                let v = *limb;
                *limb = (v << s) | carry;
                carry = v >> (32 - s);
            }
            if carry != 0 {
                self.push(carry);
            }
        }
    }

    #[inline(never)]
    fn shr1(&mut self) {
        let mut carry = 0u32;
        for limb in self.limbs.iter_mut().take(self.len).rev() {
            let v = *limb;
            *limb = (v >> 1) | carry;
            carry = v << 31;
        }
        self.trim();
    }

    /// `self += other`.
    #[inline(never)]
    fn add(&mut self, other: &Big) {
        let mut carry = 0u64;
        for i in 0..self.len.max(other.len) {
            let a = u64::from(self.limbs.get(i).copied().unwrap_or(0));
            let b = u64::from(other.limbs.get(i).copied().unwrap_or(0));
            let s = a + b + carry;
            if let Some(slot) = self.limbs.get_mut(i) {
                *slot = s as u32;
            }
            carry = s >> 32;
        }
        self.len = self.len.max(other.len);
        if carry != 0 {
            self.push(carry as u32);
        }
        self.overflow |= other.overflow;
    }

    /// `self -= other`, for `self ≥ other`.
    #[inline(never)]
    fn sub(&mut self, other: &Big) {
        let mut borrow = 0i64;
        for (i, limb) in self.limbs.iter_mut().enumerate().take(self.len) {
            let b = i64::from(other.limbs.get(i).copied().unwrap_or(0));
            let d = i64::from(*limb) - b - borrow;
            *limb = d as u32;
            borrow = i64::from(d < 0);
        }
        self.trim();
    }

    #[inline(never)]
    fn cmp(&self, other: &Big) -> Ordering {
        self.len.cmp(&other.len).then_with(|| {
            let pairs = self.used().iter().rev().zip(other.used().iter().rev());
            pairs
                .map(|(a, b)| a.cmp(b))
                .find(|o| o.is_ne())
                .unwrap_or(Ordering::Equal)
        })
    }

    /// `self + other` compared with `bound`.
    fn sum_cmp(&self, other: &Big, bound: &Big) -> Ordering {
        let mut sum = *self;
        sum.add(other);
        sum.cmp(bound)
    }
}

/// The nearest `f32` to `|text|`'s number, or `None` if it is not one (see the module doc
/// for what is accepted).
pub fn parse(text: &str) -> Option<f32> {
    let (negative, body) = match text.as_bytes().first() {
        Some(b'-') => (true, text.get(1..)?),
        Some(b'+') => (false, text.get(1..)?),
        _ => (false, text),
    };
    let magnitude = special(body).or_else(|| {
        let (digits, exponent) = decimal(body)?;
        nearest(digits, exponent)
    })?;
    Some(if negative { -magnitude } else { magnitude })
}

fn special(body: &str) -> Option<f32> {
    const WORDS: [(&str, f32); 3] = [
        ("inf", f32::INFINITY),
        ("infinity", f32::INFINITY),
        ("nan", f32::NAN),
    ];
    WORDS
        .iter()
        .find(|(word, _)| body.eq_ignore_ascii_case(word))
        .map(|&(_, v)| v)
}

/// `digits[.digits][(e|E)[+-]digits]` as `(d, e)` for the value d·10^e: `d` holds the
/// significant digits (at most [`MAX_DIGITS`]), `e` saturates far outside `f32`'s range.
fn decimal(body: &str) -> Option<(u64, i32)> {
    let (mantissa, exponent) = match body.find(['e', 'E']) {
        Some(i) => (body.get(..i)?, Some(body.get(i + 1..)?)),
        None => (body, None),
    };
    let (int, frac) = mantissa.split_once('.').unwrap_or((mantissa, ""));
    if int.is_empty() && frac.is_empty() {
        return None;
    }
    let mut d = 0u64;
    let mut significant = 0u32;
    // Zeros after the last significant digit read so far, not yet multiplied in.
    let mut zeros = 0u32;
    let mut e = 0i32;
    for (c, fractional) in int
        .bytes()
        .map(|c| (c, false))
        .chain(frac.bytes().map(|c| (c, true)))
    {
        let digit = u64::from(c.wrapping_sub(b'0'));
        if digit > 9 {
            return None;
        }
        if fractional {
            e = e.saturating_sub(1);
        }
        if digit == 0 {
            zeros += u32::from(significant > 0);
            continue;
        }
        significant += zeros + 1;
        if significant > MAX_DIGITS {
            return None;
        }
        d = d * 10u64.pow(zeros + 1) + digit;
        zeros = 0;
    }
    // Trailing zeros stay out of `d` and go to the exponent instead.
    e = e.saturating_add(zeros as i32);
    if let Some(text) = exponent {
        e = e.saturating_add(exponent_value(text)?);
    }
    Some((d, e))
}

fn exponent_value(text: &str) -> Option<i32> {
    let (negative, digits) = match text.as_bytes().first() {
        Some(b'-') => (true, text.get(1..)?),
        Some(b'+') => (false, text.get(1..)?),
        _ => (false, text),
    };
    if digits.is_empty() {
        return None;
    }
    let mut v = 0i32;
    for c in digits.bytes() {
        let digit = i32::from(c.wrapping_sub(b'0'));
        if !(0..=9).contains(&digit) {
            return None;
        }
        // Saturates: 1e100000 is as infinite for an f32 as 1e99999.
        v = v.saturating_mul(10).saturating_add(digit).min(1_000_000);
    }
    Some(if negative { -v } else { v })
}

/// The `f32` nearest to d·10^e (ties to even).
fn nearest(d: u64, e: i32) -> Option<f32> {
    if d == 0 {
        return Some(0.0);
    }
    let places = decimal_places(d);
    // d·10^e ≥ 10^39 > f32::MAX rounds to ∞; below 10^-46 < 2^-150 (half the least
    // subnormal) it rounds to zero.
    if e.saturating_add(places) > 39 {
        return Some(f32::INFINITY);
    }
    if e.saturating_add(places) <= -46 {
        return Some(0.0);
    }
    let mut num = Big::from_u64(d);
    let mut den = Big::from_u64(1);
    if e >= 0 {
        num.mul_pow10(e.unsigned_abs());
    } else {
        den.mul_pow10(e.unsigned_abs());
    }
    // q = ⌊d·10^e / 2^b⌋ with 25 or 26 bits (24 of mantissa, one to round on), or fewer for
    // a subnormal, whose last bit has the weight 2^-149.
    let mut b = (num.bit_len() as i32 - den.bit_len() as i32 - 25).max(-150);
    if b < 0 {
        num.shl(b.unsigned_abs());
    } else {
        den.shl(b.unsigned_abs());
    }
    let (mut q, mut sticky) = divide(num, den, 27)?;
    while q >= 1 << 25 {
        sticky |= q & 1 != 0;
        q >>= 1;
        b += 1;
    }
    let mut m = q >> 1;
    if q & 1 == 1 && (sticky || m & 1 == 1) {
        m += 1;
    }
    // m·2^(b+1): a normal value's m has its leading bit at 2^23 and adds it to the biased
    // exponent b + 150 − 1; a subnormal's (b = −150) has none. A rounding carry to 2^24
    // moves to the next exponent by itself.
    let biased = u32::try_from(b + 150).ok()?;
    let bits = (biased << 23) + m;
    Some(if bits >= f32::INFINITY.to_bits() {
        f32::INFINITY
    } else {
        f32::from_bits(bits)
    })
}

/// Decimal digits of `d > 0`.
fn decimal_places(mut d: u64) -> i32 {
    let mut places = 0;
    while d > 0 {
        d /= 10;
        places += 1;
    }
    places
}

/// `(⌊num/den⌋, remainder ≠ 0)` for a quotient below 2^bits; `None` if it is not, or an
/// operand overflowed.
fn divide(mut num: Big, mut den: Big, bits: u32) -> Option<(u32, bool)> {
    den.shl(bits);
    if num.overflow || den.overflow || num.cmp(&den) != Ordering::Less {
        return None;
    }
    let mut q = 0u32;
    for _ in 0..bits {
        den.shr1();
        q <<= 1;
        if num.cmp(&den) != Ordering::Less {
            num.sub(&den);
            q |= 1;
        }
    }
    Some((q, !num.is_zero()))
}

/// `f32` Display: the shortest decimal that reads back as the value, closest to it among
/// the shortest, without an exponent (`0.000001`, `1000000`), `-` for negatives (and
/// `-0`), `NaN`, `inf` — the text `{}` gives, which `set` accepts back.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shortest(pub f32);

/// `f32` Display rounded to `.1` decimals (at most 3; exact, ties to even, as `{:.N}`),
/// for status lines. Values of 10¹⁵ and more are written as [`Shortest`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fixed(pub f32, pub u8);

/// The digits d₁…dₙ of a value 0.d₁…dₙ · 10^point.
struct Digits {
    buf: [u8; 10],
    len: usize,
    point: i32,
}

impl Digits {
    fn as_str(&self) -> &str {
        core::str::from_utf8(self.buf.get(..self.len).unwrap_or(&[])).unwrap_or("")
    }
}

impl fmt::Display for Shortest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Some(v) = write_sign(f, self.0)? else {
            return Ok(());
        };
        if v == 0.0 {
            return f.write_str("0");
        }
        match shortest_digits(v) {
            Some(d) => write_point(f, &d),
            None => f.write_str("?"),
        }
    }
}

impl fmt::Display for Fixed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v.is_nan() || v.abs() >= 1e15 {
            return Shortest(v).fmt(f);
        }
        write_sign(f, v)?;
        let decimals = u32::from(self.1.min(3));
        let scale = 10u64.pow(decimals);
        // |v|·10^decimals = m·10^decimals·2^e exactly (below 2^61 here), rounded half to even.
        let (m, e) = parts(v);
        let n = u64::from(m) * scale;
        let q = match e.unsigned_abs() {
            shift if e >= 0 => n << shift,
            // n < 2^34: all of it is below half of 2^shift.
            shift if shift > 63 => 0,
            shift => {
                let q = n >> shift;
                let rest = n - (q << shift);
                let half = 1u64 << (shift - 1);
                q + u64::from(rest > half || rest == half && q % 2 == 1)
            }
        };
        write_uint(f, q / scale, 1)?;
        if decimals > 0 {
            f.write_str(".")?;
            write_uint(f, q % scale, decimals)?;
        }
        Ok(())
    }
}

/// Writes the sign (and the whole of a NaN or an infinity); the magnitude left to write.
fn write_sign(f: &mut fmt::Formatter<'_>, v: f32) -> Result<Option<f32>, fmt::Error> {
    if v.is_nan() {
        f.write_str("NaN")?;
        return Ok(None);
    }
    if v.is_sign_negative() {
        f.write_str("-")?;
    }
    if v.is_infinite() {
        f.write_str("inf")?;
        return Ok(None);
    }
    Ok(Some(v.abs()))
}

/// `n` in decimal, zero-padded to `width` digits.
fn write_uint(f: &mut fmt::Formatter<'_>, mut n: u64, width: u32) -> fmt::Result {
    let mut buf = [b'0'; 20];
    let mut start = buf.len();
    while n > 0 || buf.len() - start < width as usize {
        start -= 1;
        if let Some(slot) = buf.get_mut(start) {
            *slot = b'0' + (n % 10) as u8;
        }
        n /= 10;
    }
    f.write_str(core::str::from_utf8(buf.get(start..).unwrap_or(&[])).unwrap_or(""))
}

fn write_zeros(f: &mut fmt::Formatter<'_>, mut n: u32) -> fmt::Result {
    const ZEROS: &str = "0000000000000000";
    while n > 0 {
        let k = n.min(ZEROS.len() as u32);
        f.write_str(ZEROS.get(..k as usize).unwrap_or(""))?;
        n -= k;
    }
    Ok(())
}

/// 0.d₁…dₙ · 10^point without an exponent.
fn write_point(f: &mut fmt::Formatter<'_>, d: &Digits) -> fmt::Result {
    let digits = d.as_str();
    let len = d.len as i32;
    if d.point <= 0 {
        f.write_str("0.")?;
        write_zeros(f, d.point.unsigned_abs())?;
        f.write_str(digits)
    } else if d.point < len {
        // (`get`, not `split_at`: the digits are ASCII, and `split_at`'s char-boundary
        // panic would link core's `char` Debug formatting.)
        let point = d.point.unsigned_abs() as usize;
        f.write_str(digits.get(..point).unwrap_or(""))?;
        f.write_str(".")?;
        f.write_str(digits.get(point..).unwrap_or(""))
    } else {
        f.write_str(digits)?;
        write_zeros(f, (d.point - len).unsigned_abs())
    }
}

/// Whether `(r + gap)/s` reaches 1 (`inclusive`: also when equal).
fn reaches(r: &Big, gap: &Big, s: &Big, inclusive: bool) -> bool {
    match r.sum_cmp(gap, s) {
        Ordering::Greater => true,
        Ordering::Equal => inclusive,
        Ordering::Less => false,
    }
}

/// |v| = m·2^e, m the integer significand (with its leading bit unless subnormal).
fn parts(v: f32) -> (u32, i32) {
    let bits = v.to_bits();
    let field = (bits >> 23) & 0xFF;
    let frac = bits & 0x7F_FFFF;
    if field == 0 {
        (frac, -149)
    } else {
        (frac | 1 << 23, field as i32 - 150)
    }
}

/// The shortest digits of a finite `v > 0` (see the module doc).
fn shortest_digits(v: f32) -> Option<Digits> {
    let (m, e) = parts(v);
    let frac = m & 0x7F_FFFF;
    let field = v.to_bits() >> 23 & 0xFF;
    // v = r/s. The reals that read back as v reach half an ulp up (mp/s) and half an ulp
    // down (mm/s), a quarter at a power of two, where the ulp below halves — counted
    // there as core does, from every power of two including the least normal. They include
    // their ends when m is even (ties go to even).
    let inclusive = m % 2 == 0;
    let mut r = Big::from_u64(u64::from(m) << 2);
    let mut s = Big::from_u64(4);
    let mut mp = Big::from_u64(2);
    let mut mm = Big::from_u64(if frac == 0 && field > 0 { 1 } else { 2 });
    if e >= 0 {
        for x in [&mut r, &mut mp, &mut mm] {
            x.shl(e.unsigned_abs());
        }
    } else {
        s.shl(e.unsigned_abs());
    }
    // The decimal point: from below ⌊log10 v⌋ (1233/4096 < log10 2) up to the least
    // power of ten the interval's top stays under.
    let log2 = e + 31 - m.leading_zeros() as i32;
    let mut point = (log2 * 1233).div_euclid(4096);
    if point >= 0 {
        s.mul_pow10(point.unsigned_abs());
    } else {
        for x in [&mut r, &mut mp, &mut mm] {
            x.mul_pow10(point.unsigned_abs());
        }
    }
    while reaches(&r, &mp, &s, inclusive) {
        s.mul_small(10);
        point += 1;
    }
    let mut out = Digits {
        buf: [0; 10],
        len: 0,
        point,
    };
    loop {
        for x in [&mut r, &mut mp, &mut mm] {
            x.mul_small(10);
        }
        let mut digit = 0u8;
        while r.cmp(&s) != Ordering::Less {
            r.sub(&s);
            digit += 1;
        }
        let low = match r.cmp(&mm) {
            Ordering::Less => true,
            Ordering::Equal => inclusive,
            Ordering::Greater => false,
        };
        let high = reaches(&r, &mp, &s, inclusive);
        let done = low || high;
        // Both neighbours qualify: the nearer, up on a tie (as core rounds).
        let up = high
            && (!low || {
                let mut twice = r;
                twice.shl(1);
                twice.cmp(&s) != Ordering::Less
            });
        let slot = out.buf.get_mut(out.len)?;
        *slot = b'0' + digit + u8::from(up);
        out.len += 1;
        if done {
            break;
        }
    }
    let overflow = r.overflow || s.overflow || mp.overflow || mm.overflow;
    (!overflow).then_some(out)
}

#[cfg(test)]
mod tests;
