//! Multiplies, divides and the DSP extension: saturation and the Q flag, the parallel
//! (SIMD) additions with GE, SEL, USAD8, packing and extension (ARM ARM A7.7, "SIMD" and
//! "saturating" pseudocode).

use super::Trap;
use crate::cpu::Cpu;
use crate::fault::Fault;
use crate::insn::{Ext, Insn, LongMul, ParKind, ParOp, QOp};

/// `SignedSatQ`: `v` saturated to `bits`-bit signed, and whether it saturated.
pub(crate) fn signed_sat(v: i64, bits: u8) -> (u32, bool) {
    let max = (1i64 << (bits - 1)) - 1;
    let min = -(1i64 << (bits - 1));
    if v > max {
        (max as u32, true)
    } else if v < min {
        (min as u32, true)
    } else {
        (v as u32, false)
    }
}

/// `UnsignedSatQ`: `v` saturated to `bits`-bit unsigned, and whether it saturated.
pub(crate) fn unsigned_sat(v: i64, bits: u8) -> (u32, bool) {
    let max = if bits >= 32 {
        u32::MAX as i64
    } else {
        (1i64 << bits) - 1
    };
    if v > max {
        (max as u32, true)
    } else if v < 0 {
        (0, true)
    } else {
        (v as u32, false)
    }
}

/// SXTB … UXTAB16 on the rotated operand `v`, with the optional addend.
pub(crate) fn extend(ext: Ext, v: u32, add: Option<u32>) -> u32 {
    let a = add.unwrap_or(0);
    match ext {
        Ext::Sxtb => a.wrapping_add(v as u8 as i8 as i32 as u32),
        Ext::Sxth => a.wrapping_add(v as u16 as i16 as i32 as u32),
        Ext::Uxtb => a.wrapping_add(v & 0xFF),
        Ext::Uxth => a.wrapping_add(v & 0xFFFF),
        Ext::Sxtb16 => {
            let lo = (a as u16).wrapping_add(v as u8 as i8 as i16 as u16);
            let hi = ((a >> 16) as u16).wrapping_add((v >> 16) as u8 as i8 as i16 as u16);
            u32::from(hi) << 16 | u32::from(lo)
        }
        Ext::Uxtb16 => {
            let lo = (a as u16).wrapping_add((v & 0xFF) as u16);
            let hi = ((a >> 16) as u16).wrapping_add((v >> 16 & 0xFF) as u16);
            u32::from(hi) << 16 | u32::from(lo)
        }
    }
}

/// The lanes of a parallel operation: (lane width, operation per lane as
/// (first operand lane index, second, subtract)).
fn lanes(op: ParOp) -> (u32, [(u32, u32, bool); 4], usize) {
    match op {
        ParOp::Add16 => (
            16,
            [(0, 0, false), (1, 1, false), (0, 0, false), (0, 0, false)],
            2,
        ),
        ParOp::Sub16 => (
            16,
            [(0, 0, true), (1, 1, true), (0, 0, false), (0, 0, false)],
            2,
        ),
        // ASX: low = n.lo - m.hi, high = n.hi + m.lo.
        ParOp::Asx => (
            16,
            [(0, 1, true), (1, 0, false), (0, 0, false), (0, 0, false)],
            2,
        ),
        // SAX: low = n.lo + m.hi, high = n.hi - m.lo.
        ParOp::Sax => (
            16,
            [(0, 1, false), (1, 0, true), (0, 0, false), (0, 0, false)],
            2,
        ),
        ParOp::Add8 => (
            8,
            [(0, 0, false), (1, 1, false), (2, 2, false), (3, 3, false)],
            4,
        ),
        ParOp::Sub8 => (
            8,
            [(0, 0, true), (1, 1, true), (2, 2, true), (3, 3, true)],
            4,
        ),
    }
}

/// A parallel add/subtract: the result and the GE bits (for the plain forms).
pub(crate) fn parallel(op: ParOp, kind: ParKind, n: u32, m: u32) -> (u32, u8) {
    let (width, ops, count) = lanes(op);
    let mask = (1u32 << width) - 1;
    let signed = matches!(kind, ParKind::S | ParKind::Q | ParKind::Sh);
    let lane = |v: u32, i: u32| -> i64 {
        let raw = (v >> (i * width)) & mask;
        if signed {
            let shift = 32 - width;
            i64::from(((raw << shift) as i32) >> shift)
        } else {
            i64::from(raw)
        }
    };
    let mut result = 0u32;
    let mut ge = 0u8;
    for (i, &(a, b, sub)) in (0u32..).zip(ops.iter().take(count)) {
        let x = lane(n, a);
        let y = lane(m, b);
        let r = if sub { x - y } else { x + y };
        let out = match kind {
            ParKind::S | ParKind::U => r as u32,
            ParKind::Q => signed_sat(r, width as u8).0,
            ParKind::Uq => unsigned_sat(r, width as u8).0,
            ParKind::Sh | ParKind::Uh => (r >> 1) as u32,
        };
        result |= (out & mask) << (i * width);
        let lane_ge = match kind {
            ParKind::S => r >= 0,
            // Unsigned: GE is the carry of an add, "no borrow" of a subtract.
            ParKind::U => {
                if sub {
                    r >= 0
                } else {
                    r >= 1 << width
                }
            }
            _ => false,
        };
        if lane_ge {
            let bits_per_lane = if width == 16 { 0b11 } else { 0b1 };
            ge |= bits_per_lane << (i * (4 / count as u32));
        }
    }
    (result, ge)
}

/// SEL: each byte from `n` where its GE bit is set, else from `m`.
pub(crate) fn select(ge: u8, n: u32, m: u32) -> u32 {
    let mut mask = 0;
    for i in 0..4 {
        if ge >> i & 1 != 0 {
            mask |= 0xFF << (8 * i);
        }
    }
    n & mask | m & !mask
}

/// The sum of the absolute differences of the four byte pairs.
pub(crate) fn usad8(n: u32, m: u32) -> u32 {
    (0..4)
        .map(|i| ((n >> (8 * i)) & 0xFF).abs_diff((m >> (8 * i)) & 0xFF))
        .sum()
}

/// A signed halfword of `v` (top when `top`).
fn half(v: u32, top: bool) -> i64 {
    i64::from(if top { (v >> 16) as i16 } else { v as i16 })
}

impl Cpu {
    /// Sets Q when `saturated`.
    fn saturated(&mut self, saturated: bool) {
        if saturated {
            self.flags.q = true;
        }
    }

    /// Writes a 32-bit result that must fit, setting Q when it did not (the accumulating
    /// DSP multiplies).
    fn set_q_checked(&mut self, rd: u8, v: i64) {
        self.set_reg(rd, v as u32);
        self.saturated(v != i64::from(v as i32));
    }

    fn set_pair(&mut self, lo: u8, hi: u8, v: u64) {
        self.set_reg(lo, v as u32);
        self.set_reg(hi, (v >> 32) as u32);
    }

    fn pair(&self, lo: u8, hi: u8) -> u64 {
        u64::from(self.reg(hi)) << 32 | u64::from(self.reg(lo))
    }

    /// Multiplies, divides and the DSP-extension instructions.
    pub(crate) fn exec_dsp(&mut self, insn: Insn) -> Result<(), Trap> {
        match insn {
            Insn::Mul { s, rd, rn, rm } => {
                let v = self.reg(rn).wrapping_mul(self.reg(rm));
                self.set_reg(rd, v);
                if self.sets_flags(s) {
                    self.set_nz(v);
                }
            }
            Insn::Mla {
                rd,
                rn,
                rm,
                ra,
                sub,
            } => {
                let p = self.reg(rn).wrapping_mul(self.reg(rm));
                let a = self.reg(ra);
                self.set_reg(
                    rd,
                    if sub {
                        a.wrapping_sub(p)
                    } else {
                        a.wrapping_add(p)
                    },
                );
            }
            Insn::MulLong { op, lo, hi, rn, rm } => {
                let (n, m) = (self.reg(rn), self.reg(rm));
                let v = match op {
                    LongMul::Smull => (i64::from(n as i32) * i64::from(m as i32)) as u64,
                    LongMul::Umull => u64::from(n) * u64::from(m),
                    LongMul::Smlal => ((i64::from(n as i32) * i64::from(m as i32)) as u64)
                        .wrapping_add(self.pair(lo, hi)),
                    LongMul::Umlal => (u64::from(n) * u64::from(m)).wrapping_add(self.pair(lo, hi)),
                    LongMul::Umaal => {
                        u64::from(n) * u64::from(m)
                            + u64::from(self.reg(lo))
                            + u64::from(self.reg(hi))
                    }
                };
                self.set_pair(lo, hi, v);
            }
            Insn::Div { rd, rn, rm, signed } => {
                let (n, m) = (self.reg(rn), self.reg(rm));
                if m == 0 && self.scb.ccr & (1 << 4) != 0 {
                    return Err(Fault::DivByZero.into());
                }
                self.clock.cycles += crate::cycles::divide(n, m) - 2;
                let q = if m == 0 {
                    0
                } else if signed {
                    (n as i32).wrapping_div(m as i32) as u32
                } else {
                    n / m
                };
                self.set_reg(rd, q);
            }
            Insn::SmulXy {
                rd,
                rn,
                rm,
                ra,
                nt,
                mt,
            } => {
                let p = half(self.reg(rn), nt) * half(self.reg(rm), mt);
                if ra == 15 {
                    self.set_reg(rd, p as u32);
                } else {
                    let sum = p + i64::from(self.reg(ra) as i32);
                    self.set_q_checked(rd, sum);
                }
            }
            Insn::SmulW { rd, rn, rm, ra, mt } => {
                let p = (i64::from(self.reg(rn) as i32) * half(self.reg(rm), mt)) >> 16;
                if ra == 15 {
                    self.set_reg(rd, p as u32);
                } else {
                    let sum = p + i64::from(self.reg(ra) as i32);
                    self.set_q_checked(rd, sum);
                }
            }
            Insn::SmlalXy {
                lo,
                hi,
                rn,
                rm,
                nt,
                mt,
            } => {
                let p = half(self.reg(rn), nt) * half(self.reg(rm), mt);
                let v = (p as u64).wrapping_add(self.pair(lo, hi));
                self.set_pair(lo, hi, v);
            }
            Insn::Dual {
                rd,
                rn,
                rm,
                ra,
                sub,
                x,
            } => {
                let (n, m) = (self.reg(rn), self.reg(rm));
                let m = if x { m.rotate_right(16) } else { m };
                let p1 = half(n, false) * half(m, false);
                let p2 = half(n, true) * half(m, true);
                let mut v = if sub { p1 - p2 } else { p1 + p2 };
                if ra != 15 {
                    v += i64::from(self.reg(ra) as i32);
                }
                self.set_q_checked(rd, v);
            }
            Insn::DualLong {
                lo,
                hi,
                rn,
                rm,
                sub,
                x,
            } => {
                let (n, m) = (self.reg(rn), self.reg(rm));
                let m = if x { m.rotate_right(16) } else { m };
                let p1 = half(n, false) * half(m, false);
                let p2 = half(n, true) * half(m, true);
                let d = if sub { p1 - p2 } else { p1 + p2 };
                let v = (d as u64).wrapping_add(self.pair(lo, hi));
                self.set_pair(lo, hi, v);
            }
            Insn::Smmul {
                rd,
                rn,
                rm,
                ra,
                sub,
                round,
            } => {
                let p = i64::from(self.reg(rn) as i32) * i64::from(self.reg(rm) as i32);
                let a = if ra == 15 {
                    0
                } else {
                    i64::from(self.reg(ra) as i32) << 32
                };
                let v = if sub {
                    a.wrapping_sub(p)
                } else {
                    a.wrapping_add(p)
                };
                let v = if round {
                    v.wrapping_add(0x8000_0000)
                } else {
                    v
                };
                self.set_reg(rd, (v >> 32) as u32);
            }
            Insn::Sat {
                rd,
                rn,
                sat,
                shift,
                amount,
                unsigned,
            } => {
                let (v, _) = super::alu::shift_c(self.reg(rn), shift, u32::from(amount), false);
                let (r, q) = if unsigned {
                    unsigned_sat(i64::from(v as i32), sat)
                } else {
                    signed_sat(i64::from(v as i32), sat)
                };
                self.set_reg(rd, r);
                self.saturated(q);
            }
            Insn::Sat16 {
                rd,
                rn,
                sat,
                unsigned,
            } => {
                let v = self.reg(rn);
                let mut out = 0;
                let mut q = false;
                for i in 0..2 {
                    let x = half(v, i == 1);
                    let (r, s) = if unsigned {
                        unsigned_sat(x, sat)
                    } else {
                        signed_sat(x, sat)
                    };
                    out |= (r & 0xFFFF) << (16 * i);
                    q |= s;
                }
                self.set_reg(rd, out);
                self.saturated(q);
            }
            Insn::Pkh {
                rd,
                rn,
                rm,
                tb,
                amount,
            } => {
                let (n, m) = (self.reg(rn), self.reg(rm));
                let v = if tb {
                    let shifted = ((m as i32) >> u32::from(amount).min(31)) as u32;
                    n & 0xFFFF_0000 | shifted & 0xFFFF
                } else {
                    (m << amount) & 0xFFFF_0000 | n & 0xFFFF
                };
                self.set_reg(rd, v);
            }
            Insn::Parallel {
                op,
                kind,
                rd,
                rn,
                rm,
            } => {
                let (v, ge) = parallel(op, kind, self.reg(rn), self.reg(rm));
                self.set_reg(rd, v);
                if matches!(kind, ParKind::S | ParKind::U) {
                    self.flags.ge = ge;
                }
            }
            Insn::QArith { op, rd, rn, rm } => {
                let n = i64::from(self.reg(rn) as i32);
                let m = i64::from(self.reg(rm) as i32);
                let (doubled, q1) = match op {
                    QOp::Dadd | QOp::Dsub => signed_sat(2 * n, 32),
                    _ => (n as u32, false),
                };
                let d = i64::from(doubled as i32);
                let (v, q2) = match op {
                    QOp::Add | QOp::Dadd => signed_sat(m + d, 32),
                    QOp::Sub | QOp::Dsub => signed_sat(m - d, 32),
                };
                self.set_reg(rd, v);
                self.saturated(q1 || q2);
            }
            Insn::Sel { rd, rn, rm } => {
                let v = select(self.flags.ge, self.reg(rn), self.reg(rm));
                self.set_reg(rd, v);
            }
            Insn::Usad8 { rd, rn, rm, ra } => {
                let a = if ra == 15 { 0 } else { self.reg(ra) };
                self.set_reg(rd, a.wrapping_add(usad8(self.reg(rn), self.reg(rm))));
            }
            _ => return Err(Fault::Undefined.into()),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saturation_limits() {
        assert_eq!(signed_sat(200, 8), (127, true));
        assert_eq!(signed_sat(-129, 8), (0xFFFF_FF80, true));
        assert_eq!(signed_sat(-128, 8), (0xFFFF_FF80, false));
        assert_eq!(unsigned_sat(-1, 8), (0, true));
        assert_eq!(unsigned_sat(256, 8), (255, true));
        assert_eq!(unsigned_sat(1 << 40, 31), (0x7FFF_FFFF, true));
        assert_eq!(signed_sat(i64::from(i32::MAX) + 1, 32), (0x7FFF_FFFF, true));
    }

    #[test]
    fn parallel_adds_set_ge_per_lane() {
        // UADD16: 0xFFFF + 1 carries out of the low lane (GE[1:0] set), 1 + 1 does not.
        assert_eq!(
            parallel(ParOp::Add16, ParKind::U, 0x0001_FFFF, 0x0001_0001),
            (0x0002_0000, 0b0011)
        );
        // SSUB8: lanes 0 and 1 are non-negative.
        let (r, ge) = parallel(ParOp::Sub8, ParKind::S, 0x0502_0301, 0x0603_0101);
        assert_eq!(r, 0xFFFF_0200);
        assert_eq!(ge, 0b0011);
        // UQADD16 saturates each lane, QSUB16 too.
        assert_eq!(
            parallel(ParOp::Add16, ParKind::Uq, 0xFFF0_0010, 0x0020_0010).0,
            0xFFFF_0020
        );
        assert_eq!(
            parallel(ParOp::Sub16, ParKind::Q, 0x8000_7FFF, 0x0001_FFFF).0,
            0x8000_7FFF
        );
        // SHADD8 halves: (-2 + -2)/2 = -2, (3 + 4)/2 = 3.
        assert_eq!(
            parallel(ParOp::Add8, ParKind::Sh, 0x0000_03FE, 0x0000_04FE).0,
            0x0000_03FE
        );
        // UASX: low = n.lo - m.hi, high = n.hi + m.lo.
        assert_eq!(
            parallel(ParOp::Asx, ParKind::U, 0x0010_0005, 0x0003_0002),
            (0x0012_0002, 0b0011)
        );
    }

    #[test]
    fn select_and_sum_of_differences() {
        assert_eq!(select(0b0101, 0x11223344, 0xAABBCCDD), 0xAA22CC44);
        assert_eq!(usad8(0x01FF_0510, 0x0300_0A10), 2 + 255 + 5);
    }

    #[test]
    fn extends_add_and_rotate() {
        assert_eq!(extend(Ext::Sxtb, 0x80, None), 0xFFFF_FF80);
        assert_eq!(extend(Ext::Uxth, 0x1234_8000, Some(1)), 0x8001);
        assert_eq!(
            extend(Ext::Sxtb16, 0x00FF_0080, Some(0x0001_0001)),
            0x0000_FF81
        );
        assert_eq!(
            extend(Ext::Uxtb16, 0x12FF_34FF, Some(0x0001_0001)),
            0x0100_0100
        );
    }
}
