//! The 32-bit Thumb encodings (A5.3) other than single loads and stores: data processing,
//! branches and control, multiplies and the DSP extension.

use super::{bit, bits, decode_imm_shift, memory, reg, sign_extend, thumb_expand_imm, vfp};
use crate::insn::{DpOp, Ext, ImmCarry, Insn, LongMul, ParKind, ParOp, QOp, Reverse, Sf, Shift};

/// SP or PC: registers most 32-bit data-processing encodings forbid.
fn bad(r: u8) -> bool {
    r == 13 || r == 15
}

pub(super) fn decode(hw1: u32, hw2: u32, addr: u32) -> Insn {
    let op1 = bits(hw1, 12, 11);
    let op2 = bits(hw1, 10, 4);
    match op1 {
        0b01 => {
            if op2 & 0b1100100 == 0 {
                memory::load_store_multiple(hw1, hw2)
            } else if op2 & 0b1100100 == 0b0000100 {
                memory::dual_exclusive_table(hw1, hw2, addr)
            } else if op2 & 0b1100000 == 0b0100000 {
                dp_shifted_register(hw1, hw2)
            } else {
                vfp::decode(hw1, hw2)
            }
        }
        0b10 => {
            if bit(hw2, 15) {
                branch_misc(hw1, hw2, addr)
            } else if bit(op2, 5) {
                dp_plain_immediate(hw1, hw2, addr)
            } else {
                dp_modified_immediate(hw1, hw2)
            }
        }
        _ => {
            if op2 & 0b1000000 != 0 {
                vfp::decode(hw1, hw2)
            } else if op2 & 0b1110001 == 0 {
                memory::store_single(hw1, hw2)
            } else if op2 & 0b1100111 == 0b0000001 {
                memory::load_byte(hw1, hw2, addr)
            } else if op2 & 0b1100111 == 0b0000011 {
                memory::load_half(hw1, hw2, addr)
            } else if op2 & 0b1100111 == 0b0000101 {
                memory::load_word(hw1, hw2, addr)
            } else if op2 & 0b1110000 == 0b0100000 {
                dp_register(hw1, hw2)
            } else if op2 & 0b1111000 == 0b0110000 {
                multiply(hw1, hw2)
            } else if op2 & 0b1111000 == 0b0111000 {
                long_multiply_divide(hw1, hw2)
            } else {
                Insn::Undefined
            }
        }
    }
}

/// Which ALU operation a 4-bit data-processing opcode names, with the Rd == PC / Rn == PC
/// aliases (TST, MOV, MVN, TEQ, CMN, CMP) resolved.
fn dp_opcode(op: u32, rd: u8, rn: u8, s: bool) -> Option<DpOp> {
    let test_form = rd == 15 && s;
    Some(match op {
        0b0000 if test_form => DpOp::Tst,
        0b0000 => DpOp::And,
        0b0001 => DpOp::Bic,
        0b0010 if rn == 15 => DpOp::Mov,
        0b0010 => DpOp::Orr,
        0b0011 if rn == 15 => DpOp::Mvn,
        0b0011 => DpOp::Orn,
        0b0100 if test_form => DpOp::Teq,
        0b0100 => DpOp::Eor,
        0b1000 if test_form => DpOp::Cmn,
        0b1000 => DpOp::Add,
        0b1010 => DpOp::Adc,
        0b1011 => DpOp::Sbc,
        0b1101 if test_form => DpOp::Cmp,
        0b1101 => DpOp::Sub,
        0b1110 => DpOp::Rsb,
        _ => return None,
    })
}

/// The register constraints of the ARM ARM's data-processing encodings: which Rd/Rn/Rm
/// make an encoding UNPREDICTABLE (SP is allowed as Rn/Rd of ADD and SUB, the SP forms).
fn dp_regs_ok(op: DpOp, rd: u8, rn: u8, rm: Option<u8>) -> bool {
    let rm_ok = rm.is_none_or(|m| !bad(m));
    match op {
        DpOp::Tst | DpOp::Teq | DpOp::Cmn | DpOp::Cmp => {
            let rn_ok = if matches!(op, DpOp::Cmn | DpOp::Cmp) {
                rn != 15
            } else {
                !bad(rn)
            };
            rn_ok && rm_ok
        }
        DpOp::Mov | DpOp::Mvn => !bad(rd) && rm_ok,
        DpOp::Add | DpOp::Sub if rn == 13 => rd != 15 && rm_ok,
        DpOp::Add | DpOp::Sub => !bad(rd) && rn != 15 && rm_ok,
        _ => !bad(rd) && !bad(rn) && rm_ok,
    }
}

/// A5.3.1: data processing (modified immediate).
fn dp_modified_immediate(hw1: u32, hw2: u32) -> Insn {
    let (rn, rd) = (reg(hw1, 0), reg(hw2, 8));
    let s = bit(hw1, 4);
    let imm12 = bits(hw1, 10, 10) << 11 | bits(hw2, 14, 12) << 8 | bits(hw2, 7, 0);
    let Some(op) = dp_opcode(bits(hw1, 8, 5), rd, rn, s) else {
        return Insn::Undefined;
    };
    let Some((imm, carry)) = thumb_expand_imm(imm12) else {
        return Insn::Undefined;
    };
    if !dp_regs_ok(op, rd, rn, None) {
        return Insn::Undefined;
    }
    let s = if s { Sf::Yes } else { Sf::No };
    let carry = match op {
        DpOp::Add | DpOp::Adc | DpOp::Sub | DpOp::Sbc | DpOp::Rsb | DpOp::Cmp | DpOp::Cmn => {
            ImmCarry::Keep
        }
        _ => carry,
    };
    Insn::DpImm {
        op,
        s,
        rd,
        rn,
        carry,
        imm,
    }
}

/// A5.3.3: data processing (plain binary immediate).
fn dp_plain_immediate(hw1: u32, hw2: u32, addr: u32) -> Insn {
    let (rn, rd) = (reg(hw1, 0), reg(hw2, 8));
    let imm12 = bits(hw1, 10, 10) << 11 | bits(hw2, 14, 12) << 8 | bits(hw2, 7, 0);
    let imm3_2 = (bits(hw2, 14, 12) << 2 | bits(hw2, 7, 6)) as u8;
    let low5 = bits(hw2, 4, 0) as u8;
    let plain = |op, rn, imm| Insn::DpImm {
        op,
        s: Sf::No,
        rd,
        rn,
        carry: ImmCarry::Keep,
        imm,
    };
    match bits(hw1, 8, 4) {
        0b00000 | 0b01010 if rn == 15 => {
            // ADR: the value is Align(PC, 4) ± imm12.
            if bad(rd) {
                return Insn::Undefined;
            }
            let base = super::pc_aligned(addr);
            let value = if bit(hw1, 7) {
                base.wrapping_sub(imm12)
            } else {
                base.wrapping_add(imm12)
            };
            plain(DpOp::Mov, 15, value)
        }
        op @ (0b00000 | 0b01010) => {
            let op = if op == 0 { DpOp::Add } else { DpOp::Sub };
            if !dp_regs_ok(op, rd, rn, None) {
                return Insn::Undefined;
            }
            plain(op, rn, imm12)
        }
        0b00100 | 0b01100 => {
            if bad(rd) {
                return Insn::Undefined;
            }
            let imm16 = bits(hw1, 3, 0) << 12 | imm12;
            if bit(hw1, 7) {
                Insn::MovT {
                    rd,
                    imm: imm16 as u16,
                }
            } else {
                plain(DpOp::Mov, 15, imm16)
            }
        }
        op @ (0b10000 | 0b10010 | 0b11000 | 0b11010) => {
            if bad(rd) || bad(rn) || bit(hw2, 5) {
                return Insn::Undefined;
            }
            let unsigned = op >= 0b11000;
            let asr = bit(op, 1);
            if asr && imm3_2 == 0 {
                // SSAT16 / USAT16: bits 5:4 of the second halfword are zero.
                if bits(hw2, 5, 4) != 0 {
                    return Insn::Undefined;
                }
                let field = bits(hw2, 3, 0) as u8;
                return Insn::Sat16 {
                    rd,
                    rn,
                    sat: if unsigned { field } else { field + 1 },
                    unsigned,
                };
            }
            let (shift, amount) = decode_imm_shift(if asr { 2 } else { 0 }, u32::from(imm3_2));
            Insn::Sat {
                rd,
                rn,
                sat: if unsigned { low5 } else { low5 + 1 },
                shift,
                amount,
                unsigned,
            }
        }
        op @ (0b10100 | 0b11100) => {
            let width = low5 + 1;
            if bad(rd) || bad(rn) || imm3_2 + width > 32 || bit(hw2, 5) {
                return Insn::Undefined;
            }
            Insn::Bfx {
                rd,
                rn,
                lsb: imm3_2,
                width,
                signed: op == 0b10100,
            }
        }
        0b10110 => {
            if bad(rd) || rn == 13 || low5 < imm3_2 || bit(hw2, 5) {
                return Insn::Undefined;
            }
            if rn == 15 {
                Insn::Bfc {
                    rd,
                    lsb: imm3_2,
                    msb: low5,
                }
            } else {
                Insn::Bfi {
                    rd,
                    rn,
                    lsb: imm3_2,
                    msb: low5,
                }
            }
        }
        _ => Insn::Undefined,
    }
}

/// A5.3.11: data processing (shifted register).
fn dp_shifted_register(hw1: u32, hw2: u32) -> Insn {
    let (rn, rd, rm) = (reg(hw1, 0), reg(hw2, 8), reg(hw2, 0));
    let s = bit(hw1, 4);
    let imm5 = bits(hw2, 14, 12) << 2 | bits(hw2, 7, 6);
    let ty = bits(hw2, 5, 4);
    if bit(hw2, 15) {
        return Insn::Undefined;
    }
    let opcode = bits(hw1, 8, 5);
    if opcode == 0b0110 {
        // PKHBT / PKHTB: S and bit 4 of the type must be zero.
        if s || bit(hw2, 4) || bad(rd) || bad(rn) || bad(rm) {
            return Insn::Undefined;
        }
        let tb = bit(hw2, 5);
        let (_, amount) = decode_imm_shift(if tb { 2 } else { 0 }, imm5);
        return Insn::Pkh {
            rd,
            rn,
            rm,
            tb,
            amount,
        };
    }
    let Some(op) = dp_opcode(opcode, rd, rn, s) else {
        return Insn::Undefined;
    };
    if !dp_regs_ok(op, rd, rn, Some(rm)) {
        // MOV.W with SP: `mov sp, rm` and `mov rd, sp` are allowed without S and shift.
        let sp_move = op == DpOp::Mov
            && !s
            && imm5 == 0
            && ty == 0
            && rd != 15
            && rm != 15
            && !(rd == 13 && rm == 13);
        // ADD/SUB/CMP with SP as Rn take SP as a plain operand.
        if !sp_move {
            return Insn::Undefined;
        }
    }
    if matches!(op, DpOp::Add | DpOp::Sub) && rn == 13 {
        // ADD/SUB (SP plus register): only LSL #0..3 is predictable for a SP destination.
        if rd == 13 && (ty != 0 || imm5 > 3) {
            return Insn::Undefined;
        }
    }
    let (shift, amount) = decode_imm_shift(ty, imm5);
    Insn::DpReg {
        op,
        s: if s { Sf::Yes } else { Sf::No },
        rd,
        rn,
        rm,
        shift,
        amount,
    }
}

/// A5.3.12: data processing (register): shifts by register, extends, parallel arithmetic,
/// miscellaneous operations.
fn dp_register(hw1: u32, hw2: u32) -> Insn {
    let (rn, rd, rm) = (reg(hw1, 0), reg(hw2, 8), reg(hw2, 0));
    let op1 = bits(hw1, 7, 4);
    let op2 = bits(hw2, 7, 4);
    if bits(hw2, 15, 12) != 0b1111 {
        return Insn::Undefined;
    }
    if op1 < 0b1000 && op2 == 0 {
        if bad(rd) || bad(rn) || bad(rm) {
            return Insn::Undefined;
        }
        let shift = match op1 >> 1 {
            0 => Shift::Lsl,
            1 => Shift::Lsr,
            2 => Shift::Asr,
            _ => Shift::Ror,
        };
        return Insn::ShiftReg {
            shift,
            s: if bit(op1, 0) { Sf::Yes } else { Sf::No },
            rd,
            rn,
            rm,
        };
    }
    if op1 < 0b0110 && bit(op2, 3) {
        if bad(rd) || bad(rm) || rn == 13 || bit(hw2, 6) {
            return Insn::Undefined;
        }
        let ext = match op1 {
            0 => Ext::Sxth,
            1 => Ext::Uxth,
            2 => Ext::Sxtb16,
            3 => Ext::Uxtb16,
            4 => Ext::Sxtb,
            _ => Ext::Uxtb,
        };
        return Insn::Extend {
            ext,
            rd,
            rn,
            rm,
            rot: (bits(hw2, 5, 4) * 8) as u8,
        };
    }
    if op1 >= 0b1000 && op2 < 0b1000 {
        if bad(rd) || bad(rn) || bad(rm) || bit(op2, 3) {
            return Insn::Undefined;
        }
        return parallel(op1 & 0b111, op2, rd, rn, rm);
    }
    if op1 & 0b1100 == 0b1000 && op2 & 0b1100 == 0b1000 {
        return misc_operations(op1 & 0b11, op2 & 0b11, rd, rn, rm);
    }
    Insn::Undefined
}

/// A5.3.13: parallel addition and subtraction.
fn parallel(op1: u32, op2: u32, rd: u8, rn: u8, rm: u8) -> Insn {
    let op = match op1 {
        0b001 => ParOp::Add16,
        0b010 => ParOp::Asx,
        0b110 => ParOp::Sax,
        0b101 => ParOp::Sub16,
        0b000 => ParOp::Add8,
        0b100 => ParOp::Sub8,
        _ => return Insn::Undefined,
    };
    let kind = match op2 {
        0b000 => ParKind::S,
        0b001 => ParKind::Q,
        0b010 => ParKind::Sh,
        0b100 => ParKind::U,
        0b101 => ParKind::Uq,
        0b110 => ParKind::Uh,
        _ => return Insn::Undefined,
    };
    Insn::Parallel {
        op,
        kind,
        rd,
        rn,
        rm,
    }
}

/// A5.3.14: miscellaneous operations (saturating add/sub, reversals, SEL, CLZ).
fn misc_operations(op1: u32, op2: u32, rd: u8, rn: u8, rm: u8) -> Insn {
    if bad(rd) || bad(rn) || bad(rm) {
        return Insn::Undefined;
    }
    // The single-operand forms repeat Rm in the Rn field.
    let consistent = rn == rm;
    match (op1, op2) {
        (0, op) => Insn::QArith {
            op: match op {
                0 => QOp::Add,
                1 => QOp::Dadd,
                2 => QOp::Sub,
                _ => QOp::Dsub,
            },
            rd,
            rn,
            rm,
        },
        (1, op) if consistent => Insn::Rev {
            op: match op {
                0 => Reverse::Rev,
                1 => Reverse::Rev16,
                2 => Reverse::Rbit,
                _ => Reverse::Revsh,
            },
            rd,
            rm,
        },
        (2, 0) => Insn::Sel { rd, rn, rm },
        (3, 0) if consistent => Insn::Clz { rd, rm },
        _ => Insn::Undefined,
    }
}

/// A5.3.16: multiply, multiply accumulate and absolute difference.
fn multiply(hw1: u32, hw2: u32) -> Insn {
    let (rn, ra, rd, rm) = (reg(hw1, 0), reg(hw2, 12), reg(hw2, 8), reg(hw2, 0));
    let op1 = bits(hw1, 6, 4);
    let op2 = bits(hw2, 5, 4);
    if bits(hw2, 7, 6) != 0 || bad(rd) || bad(rn) || bad(rm) || ra == 13 {
        return Insn::Undefined;
    }
    let (hi, lo) = (bit(op2, 1), bit(op2, 0));
    match op1 {
        0b000 => match op2 {
            0 if ra == 15 => Insn::Mul {
                s: Sf::No,
                rd,
                rn,
                rm,
            },
            0 | 1 if ra != 15 => Insn::Mla {
                rd,
                rn,
                rm,
                ra,
                sub: op2 == 1,
            },
            _ => Insn::Undefined,
        },
        0b001 => Insn::SmulXy {
            rd,
            rn,
            rm,
            ra,
            nt: hi,
            mt: lo,
        },
        0b010 | 0b100 if !hi => Insn::Dual {
            rd,
            rn,
            rm,
            ra,
            sub: op1 == 0b100,
            x: lo,
        },
        0b011 if !hi => Insn::SmulW {
            rd,
            rn,
            rm,
            ra,
            mt: lo,
        },
        0b101 if !hi => Insn::Smmul {
            rd,
            rn,
            rm,
            ra,
            sub: false,
            round: lo,
        },
        0b110 if !hi && ra != 15 => Insn::Smmul {
            rd,
            rn,
            rm,
            ra,
            sub: true,
            round: lo,
        },
        0b111 if op2 == 0 => Insn::Usad8 { rd, rn, rm, ra },
        _ => Insn::Undefined,
    }
}

/// A5.3.17: long multiply, long multiply accumulate and divide.
fn long_multiply_divide(hw1: u32, hw2: u32) -> Insn {
    let (rn, lo, hi, rm) = (reg(hw1, 0), reg(hw2, 12), reg(hw2, 8), reg(hw2, 0));
    let op1 = bits(hw1, 6, 4);
    let op2 = bits(hw2, 7, 4);
    if bad(rn) || bad(rm) {
        return Insn::Undefined;
    }
    if op2 == 0b1111 && (op1 == 0b001 || op1 == 0b011) {
        // SDIV/UDIV: the RdLo field holds 1111.
        if lo != 15 || bad(hi) {
            return Insn::Undefined;
        }
        return Insn::Div {
            rd: hi,
            rn,
            rm,
            signed: op1 == 0b001,
        };
    }
    if bad(lo) || bad(hi) || lo == hi {
        return Insn::Undefined;
    }
    let long = |op| Insn::MulLong { op, lo, hi, rn, rm };
    match (op1, op2) {
        (0b000, 0) => long(LongMul::Smull),
        (0b010, 0) => long(LongMul::Umull),
        (0b100, 0) => long(LongMul::Smlal),
        (0b110, 0) => long(LongMul::Umlal),
        (0b110, 0b0110) => long(LongMul::Umaal),
        (0b100, 0b1000..=0b1011) => Insn::SmlalXy {
            lo,
            hi,
            rn,
            rm,
            nt: bit(op2, 1),
            mt: bit(op2, 0),
        },
        (0b100 | 0b101, 0b1100 | 0b1101) => Insn::DualLong {
            lo,
            hi,
            rn,
            rm,
            sub: op1 == 0b101,
            x: bit(op2, 0),
        },
        _ => Insn::Undefined,
    }
}

/// A5.3.4: branches and miscellaneous control.
fn branch_misc(hw1: u32, hw2: u32, addr: u32) -> Insn {
    let op = bits(hw1, 10, 4);
    let op1 = bits(hw2, 14, 12);
    let s = bits(hw1, 10, 10);
    let (j1, j2) = (bits(hw2, 13, 13), bits(hw2, 11, 11));
    let next = addr.wrapping_add(4);
    if op1 & 0b101 == 0b000 {
        if op & 0b0111000 != 0b0111000 {
            let imm = s << 20 | j2 << 19 | j1 << 18 | bits(hw1, 5, 0) << 12 | bits(hw2, 10, 0) << 1;
            return Insn::BCond {
                cond: bits(hw1, 9, 6) as u8,
                target: next.wrapping_add(sign_extend(imm, 21)),
            };
        }
        return match op {
            0b0111000 | 0b0111001 => {
                let rn = reg(hw1, 0);
                let mask = bits(hw2, 11, 10) as u8;
                let sysm = bits(hw2, 7, 0) as u8;
                if bad(rn)
                    || !sysm_valid(sysm)
                    || (sysm < 8 && mask == 0)
                    || (sysm >= 8 && mask != 0b10)
                {
                    return Insn::Undefined;
                }
                Insn::Msr { rn, sysm, mask }
            }
            0b0111010 => {
                if bits(hw2, 10, 8) != 0 {
                    return Insn::Undefined;
                }
                match bits(hw2, 7, 0) {
                    2 => Insn::Wfe,
                    3 => Insn::Wfi,
                    4 => Insn::Sev,
                    _ => Insn::Nop,
                }
            }
            0b0111011 => match bits(hw2, 7, 4) {
                0b0010 => Insn::Clrex,
                0b0100..=0b0110 => Insn::Barrier,
                _ => Insn::Undefined,
            },
            0b0111110 | 0b0111111 => {
                let rd = reg(hw2, 8);
                let sysm = bits(hw2, 7, 0) as u8;
                if bad(rd) || !sysm_valid(sysm) {
                    return Insn::Undefined;
                }
                Insn::Mrs { rd, sysm }
            }
            0b1111111 if op1 == 0b010 => Insn::Udf,
            _ => Insn::Undefined,
        };
    }
    let i1 = !(j1 ^ s) & 1;
    let i2 = !(j2 ^ s) & 1;
    let imm = s << 24 | i1 << 23 | i2 << 22 | bits(hw1, 9, 0) << 12 | bits(hw2, 10, 0) << 1;
    let target = next.wrapping_add(sign_extend(imm, 25));
    match op1 {
        0b001 | 0b011 => Insn::B { target },
        0b101 | 0b111 => Insn::Bl { target },
        _ => Insn::Undefined,
    }
}

/// The special registers MRS and MSR name (B5.2.2).
fn sysm_valid(sysm: u8) -> bool {
    matches!(sysm, 0..=3 | 5..=9 | 16..=20)
}
