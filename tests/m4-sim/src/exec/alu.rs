//! Integer data processing: the shifter with its carry out (A7.4.2 `Shift_C`), `AddWithCarry`,
//! the ALU operations with their flag rules, bit fields and reversals.

use crate::cpu::Cpu;
use crate::insn::{DpOp, Reverse, Shift};

/// `Shift_C`: `value` shifted by `amount` (any value; 0 leaves value and carry alone),
/// with the carry out.
#[inline(always)]
pub(crate) fn shift_c(value: u32, shift: Shift, amount: u32, carry_in: bool) -> (u32, bool) {
    if amount == 0 {
        return (value, carry_in);
    }
    match shift {
        Shift::Lsl => {
            if amount < 32 {
                (value << amount, value >> (32 - amount) & 1 != 0)
            } else if amount == 32 {
                (0, value & 1 != 0)
            } else {
                (0, false)
            }
        }
        Shift::Lsr => {
            if amount < 32 {
                (value >> amount, value >> (amount - 1) & 1 != 0)
            } else if amount == 32 {
                (0, value >> 31 != 0)
            } else {
                (0, false)
            }
        }
        Shift::Asr => {
            let a = amount.min(32);
            let v = value as i32;
            let result = if a >= 32 { v >> 31 } else { v >> a };
            (result as u32, (v >> (a - 1).min(31)) & 1 != 0)
        }
        Shift::Ror => {
            let result = value.rotate_right(amount % 32);
            (result, result >> 31 != 0)
        }
        Shift::Rrx => (u32::from(carry_in) << 31 | value >> 1, value & 1 != 0),
    }
}

/// `AddWithCarry`: result, carry out, overflow.
#[inline(always)]
pub(crate) fn add_with_carry(x: u32, y: u32, carry_in: bool) -> (u32, bool, bool) {
    let (s1, c1) = x.overflowing_add(y);
    let (result, c2) = s1.overflowing_add(u32::from(carry_in));
    let overflow = ((x ^ result) & (y ^ result)) >> 31 != 0;
    (result, c1 || c2, overflow)
}

/// Bits `lsb..=msb` set.
pub(crate) fn bit_mask(lsb: u8, msb: u8) -> u32 {
    let width = u32::from(msb - lsb) + 1;
    let ones = if width >= 32 {
        u32::MAX
    } else {
        (1 << width) - 1
    };
    ones << lsb
}

/// SBFX/UBFX: `width` bits of `v` from `lsb`, sign- or zero-extended.
pub(crate) fn extract(v: u32, lsb: u8, width: u8, signed: bool) -> u32 {
    let up = 32 - u32::from(lsb) - u32::from(width);
    let left = v << up;
    let down = up + u32::from(lsb);
    if signed {
        ((left as i32) >> down) as u32
    } else {
        left >> down
    }
}

/// REV, REV16, REVSH, RBIT.
pub(crate) fn reverse(op: Reverse, v: u32) -> u32 {
    match op {
        Reverse::Rev => v.swap_bytes(),
        Reverse::Rev16 => (v & 0x00FF_00FF) << 8 | (v >> 8) & 0x00FF_00FF,
        Reverse::Revsh => ((v as u16).swap_bytes() as i16) as i32 as u32,
        Reverse::Rbit => v.reverse_bits(),
    }
}

impl Cpu {
    /// One ALU operation of the data-processing group on `a` (Rn) and the shifted or
    /// immediate operand `b` with its shifter carry `c`.
    #[inline(always)]
    pub(crate) fn data_processing(
        &mut self,
        op: DpOp,
        setflags: bool,
        rd: u8,
        a: u32,
        b: u32,
        c: bool,
    ) {
        let logic = |cpu: &mut Cpu, result: u32, write: bool| {
            if write {
                cpu.set_reg(rd, result);
            }
            if setflags {
                cpu.set_nz(result);
                cpu.flags.c = c;
            }
        };
        let arith = |cpu: &mut Cpu, (result, carry, overflow): (u32, bool, bool), write: bool| {
            if write {
                cpu.set_reg(rd, result);
            }
            if setflags {
                cpu.set_nz(result);
                cpu.flags.c = carry;
                cpu.flags.v = overflow;
            }
        };
        match op {
            DpOp::And => logic(self, a & b, true),
            DpOp::Bic => logic(self, a & !b, true),
            DpOp::Orr => logic(self, a | b, true),
            DpOp::Orn => logic(self, a | !b, true),
            DpOp::Eor => logic(self, a ^ b, true),
            DpOp::Mov => logic(self, b, true),
            DpOp::Mvn => logic(self, !b, true),
            DpOp::Tst => logic(self, a & b, false),
            DpOp::Teq => logic(self, a ^ b, false),
            DpOp::Add => arith(self, add_with_carry(a, b, false), true),
            DpOp::Adc => arith(self, add_with_carry(a, b, self.flags.c), true),
            DpOp::Sub => arith(self, add_with_carry(a, !b, true), true),
            DpOp::Sbc => arith(self, add_with_carry(a, !b, self.flags.c), true),
            DpOp::Rsb => arith(self, add_with_carry(!a, b, true), true),
            DpOp::Cmp => arith(self, add_with_carry(a, !b, true), false),
            DpOp::Cmn => arith(self, add_with_carry(a, b, false), false),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifts_carry_out_the_last_bit_and_saturate_past_32() {
        assert_eq!(shift_c(0x8000_0001, Shift::Lsl, 1, false), (2, true));
        assert_eq!(shift_c(1, Shift::Lsl, 32, false), (0, true));
        assert_eq!(shift_c(1, Shift::Lsl, 33, true), (0, false));
        assert_eq!(shift_c(0x8000_0000, Shift::Lsr, 32, false), (0, true));
        assert_eq!(shift_c(0xFFFF_FFFF, Shift::Lsr, 40, true), (0, false));
        assert_eq!(
            shift_c(0x8000_0000, Shift::Asr, 40, false),
            (0xFFFF_FFFF, true)
        );
        assert_eq!(shift_c(0x4000_0000, Shift::Asr, 32, true), (0, false));
        assert_eq!(
            shift_c(0x0000_0003, Shift::Ror, 1, false),
            (0x8000_0001, true)
        );
        assert_eq!(
            shift_c(0x8000_0000, Shift::Ror, 32, false),
            (0x8000_0000, true)
        );
        assert_eq!(
            shift_c(0x7FFF_FFFF, Shift::Ror, 64, true),
            (0x7FFF_FFFF, false)
        );
        assert_eq!(shift_c(3, Shift::Rrx, 1, true), (0x8000_0001, true));
        // A zero register shift leaves the carry alone.
        assert_eq!(shift_c(5, Shift::Lsr, 0, true), (5, true));
    }

    #[test]
    fn add_with_carry_gives_the_manuals_flags() {
        assert_eq!(
            add_with_carry(0x7FFF_FFFF, 1, false),
            (0x8000_0000, false, true)
        );
        assert_eq!(add_with_carry(0xFFFF_FFFF, 1, false), (0, true, false));
        // 5 - 7 as AddWithCarry(5, NOT 7, 1): borrow means carry clear.
        assert_eq!(add_with_carry(5, !7, true), (0xFFFF_FFFE, false, false));
        assert_eq!(add_with_carry(7, !5, true), (2, true, false));
        assert_eq!(
            add_with_carry(0x8000_0000, !1, true),
            (0x7FFF_FFFF, true, true)
        );
        assert_eq!(add_with_carry(0xFFFF_FFFF, 0, true), (0, true, false));
    }

    #[test]
    fn bit_fields() {
        assert_eq!(bit_mask(4, 7), 0xF0);
        assert_eq!(bit_mask(0, 31), u32::MAX);
        assert_eq!(extract(0xABCD_1234, 8, 8, false), 0x12);
        assert_eq!(extract(0x0000_8000, 12, 4, true), 0xFFFF_FFF8);
        assert_eq!(extract(0xF000_0000, 28, 4, true), 0xFFFF_FFFF);
        assert_eq!(extract(0x8000_0000, 0, 32, false), 0x8000_0000);
    }

    #[test]
    fn reversals() {
        assert_eq!(reverse(Reverse::Rev, 0x1122_3344), 0x4433_2211);
        assert_eq!(reverse(Reverse::Rev16, 0x1122_3344), 0x2211_4433);
        assert_eq!(reverse(Reverse::Revsh, 0x0000_0080), 0xFFFF_8000);
        assert_eq!(reverse(Reverse::Rbit, 1), 0x8000_0000);
    }
}
