//! The 16-bit Thumb encodings (A5.2).

use super::{bit, bits, pc_aligned, sign_extend};
use crate::insn::{DpOp, Ext, ImmCarry, Index, Insn, MemOp, Reverse, Sf, Shift};

pub(super) fn decode(hw: u32, addr: u32) -> Insn {
    match bits(hw, 15, 10) {
        0b000000..=0b001111 => shift_add_sub_mov_cmp(hw),
        0b010000 => data_processing(hw),
        0b010001 => special_and_branch(hw),
        0b010010 | 0b010011 => Insn::MemLit {
            op: MemOp::Ldr,
            rt: r3(hw, 8),
            addr: pc_aligned(addr).wrapping_add(bits(hw, 7, 0) << 2),
        },
        0b010100..=0b100111 => load_store(hw),
        0b101000 | 0b101001 => Insn::DpImm {
            op: DpOp::Mov,
            s: Sf::No,
            rd: r3(hw, 8),
            rn: 15,
            carry: ImmCarry::Keep,
            imm: pc_aligned(addr).wrapping_add(bits(hw, 7, 0) << 2),
        },
        0b101010 | 0b101011 => Insn::DpImm {
            op: DpOp::Add,
            s: Sf::No,
            rd: r3(hw, 8),
            rn: 13,
            carry: ImmCarry::Keep,
            imm: bits(hw, 7, 0) << 2,
        },
        0b101100..=0b101111 => misc(hw, addr),
        0b110000 | 0b110001 => {
            let rn = r3(hw, 8);
            let regs = bits(hw, 7, 0) as u16;
            if regs == 0 {
                return Insn::Undefined;
            }
            Insn::Multi {
                load: false,
                rn,
                regs,
                wback: true,
                db: false,
            }
        }
        0b110010 | 0b110011 => {
            let rn = r3(hw, 8);
            let regs = bits(hw, 7, 0) as u16;
            if regs == 0 {
                return Insn::Undefined;
            }
            Insn::Multi {
                load: true,
                rn,
                regs,
                wback: regs & (1 << rn) == 0,
                db: false,
            }
        }
        0b110100..=0b110111 => match bits(hw, 11, 8) {
            0b1110 => Insn::Udf,
            0b1111 => Insn::Svc,
            cond => Insn::BCond {
                cond: cond as u8,
                target: addr
                    .wrapping_add(4)
                    .wrapping_add(sign_extend(bits(hw, 7, 0) << 1, 9)),
            },
        },
        0b111000 | 0b111001 => Insn::B {
            target: addr
                .wrapping_add(4)
                .wrapping_add(sign_extend(bits(hw, 10, 0) << 1, 12)),
        },
        _ => Insn::Undefined,
    }
}

/// A 3-bit register field at `lo`.
fn r3(hw: u32, lo: u32) -> u8 {
    bits(hw, lo + 2, lo) as u8
}

/// A5.2.1: shift (immediate), add, subtract, move, compare.
fn shift_add_sub_mov_cmp(hw: u32) -> Insn {
    let (rd, rn, rm) = (r3(hw, 0), r3(hw, 3), r3(hw, 6));
    let imm5 = bits(hw, 10, 6);
    let shifted = |shift, amount| Insn::DpReg {
        op: DpOp::Mov,
        s: Sf::OutsideIt,
        rd,
        rn: 15,
        rm: rn,
        shift,
        amount,
    };
    let imm = |op, s, rd, rn, imm| Insn::DpImm {
        op,
        s,
        rd,
        rn,
        carry: ImmCarry::Keep,
        imm,
    };
    match bits(hw, 13, 9) {
        // LSL #0 is MOVS (register) T2, which sets the flags even in an IT block (where it is
        // UNPREDICTABLE; we execute it as written).
        0b00000..=0b00011 if imm5 == 0 => Insn::DpReg {
            op: DpOp::Mov,
            s: Sf::Yes,
            rd,
            rn: 15,
            rm: rn,
            shift: Shift::Lsl,
            amount: 0,
        },
        0b00000..=0b00011 => shifted(Shift::Lsl, imm5 as u8),
        0b00100..=0b00111 => shifted(Shift::Lsr, if imm5 == 0 { 32 } else { imm5 as u8 }),
        0b01000..=0b01011 => shifted(Shift::Asr, if imm5 == 0 { 32 } else { imm5 as u8 }),
        0b01100 | 0b01101 => Insn::DpReg {
            op: if bit(hw, 9) { DpOp::Sub } else { DpOp::Add },
            s: Sf::OutsideIt,
            rd,
            rn,
            rm,
            shift: Shift::Lsl,
            amount: 0,
        },
        0b01110 => imm(DpOp::Add, Sf::OutsideIt, rd, rn, u32::from(rm)),
        0b01111 => imm(DpOp::Sub, Sf::OutsideIt, rd, rn, u32::from(rm)),
        op => {
            let rdn = r3(hw, 8);
            let imm8 = bits(hw, 7, 0);
            match op >> 2 {
                0b100 => imm(DpOp::Mov, Sf::OutsideIt, rdn, 15, imm8),
                0b101 => imm(DpOp::Cmp, Sf::Yes, 15, rdn, imm8),
                0b110 => imm(DpOp::Add, Sf::OutsideIt, rdn, rdn, imm8),
                _ => imm(DpOp::Sub, Sf::OutsideIt, rdn, rdn, imm8),
            }
        }
    }
}

/// A5.2.2: data processing on low registers.
fn data_processing(hw: u32) -> Insn {
    let (rdn, rm) = (r3(hw, 0), r3(hw, 3));
    let reg = |op, rd, rn, rm, s| Insn::DpReg {
        op,
        s,
        rd,
        rn,
        rm,
        shift: Shift::Lsl,
        amount: 0,
    };
    let by_reg = |shift| Insn::ShiftReg {
        shift,
        s: Sf::OutsideIt,
        rd: rdn,
        rn: rdn,
        rm,
    };
    match bits(hw, 9, 6) {
        0b0000 => reg(DpOp::And, rdn, rdn, rm, Sf::OutsideIt),
        0b0001 => reg(DpOp::Eor, rdn, rdn, rm, Sf::OutsideIt),
        0b0010 => by_reg(Shift::Lsl),
        0b0011 => by_reg(Shift::Lsr),
        0b0100 => by_reg(Shift::Asr),
        0b0101 => reg(DpOp::Adc, rdn, rdn, rm, Sf::OutsideIt),
        0b0110 => reg(DpOp::Sbc, rdn, rdn, rm, Sf::OutsideIt),
        0b0111 => by_reg(Shift::Ror),
        0b1000 => reg(DpOp::Tst, 15, rdn, rm, Sf::Yes),
        0b1001 => Insn::DpImm {
            op: DpOp::Rsb,
            s: Sf::OutsideIt,
            rd: rdn,
            rn: rm,
            carry: ImmCarry::Keep,
            imm: 0,
        },
        0b1010 => reg(DpOp::Cmp, 15, rdn, rm, Sf::Yes),
        0b1011 => reg(DpOp::Cmn, 15, rdn, rm, Sf::Yes),
        0b1100 => reg(DpOp::Orr, rdn, rdn, rm, Sf::OutsideIt),
        0b1101 => Insn::Mul {
            s: Sf::OutsideIt,
            rd: rdn,
            rn: rm,
            rm: rdn,
        },
        0b1110 => reg(DpOp::Bic, rdn, rdn, rm, Sf::OutsideIt),
        _ => reg(DpOp::Mvn, rdn, 15, rm, Sf::OutsideIt),
    }
}

/// A5.2.3: special data instructions and branch and exchange (high registers).
fn special_and_branch(hw: u32) -> Insn {
    let rdn = (bits(hw, 7, 7) << 3 | bits(hw, 2, 0)) as u8;
    let rm = bits(hw, 6, 3) as u8;
    let reg = |op, rd, rn| Insn::DpReg {
        op,
        s: if op == DpOp::Cmp { Sf::Yes } else { Sf::No },
        rd,
        rn,
        rm,
        shift: Shift::Lsl,
        amount: 0,
    };
    match bits(hw, 9, 6) {
        0b0000..=0b0011 => {
            if rdn == 15 && rm == 15 {
                Insn::Undefined
            } else {
                reg(DpOp::Add, rdn, rdn)
            }
        }
        0b0100 => Insn::Undefined,
        0b0101..=0b0111 => {
            if (rdn < 8 && rm < 8) || rdn == 15 || rm == 15 {
                Insn::Undefined
            } else {
                reg(DpOp::Cmp, 15, rdn)
            }
        }
        0b1000..=0b1011 => reg(DpOp::Mov, rdn, 15),
        op => {
            if bits(hw, 2, 0) != 0 {
                Insn::Undefined
            } else if op <= 0b1101 {
                Insn::Bx { rm }
            } else if rm == 15 {
                Insn::Undefined
            } else {
                Insn::BlxReg { rm }
            }
        }
    }
}

/// A5.2.4: load/store single data item.
fn load_store(hw: u32) -> Insn {
    let (rt, rn, rm) = (r3(hw, 0), r3(hw, 3), r3(hw, 6));
    let imm5 = bits(hw, 10, 6) as u16;
    let load = bit(hw, 11);
    let imm = |op, rt, rn, imm| Insn::MemImm {
        op,
        rt,
        rn,
        index: Index::Offset,
        add: true,
        user: false,
        imm,
    };
    match bits(hw, 15, 12) {
        0b0101 => Insn::MemReg {
            op: match bits(hw, 11, 9) {
                0 => MemOp::Str,
                1 => MemOp::Strh,
                2 => MemOp::Strb,
                3 => MemOp::Ldrsb,
                4 => MemOp::Ldr,
                5 => MemOp::Ldrh,
                6 => MemOp::Ldrb,
                _ => MemOp::Ldrsh,
            },
            rt,
            rn,
            rm,
            amount: 0,
        },
        0b0110 => imm(
            if load { MemOp::Ldr } else { MemOp::Str },
            rt,
            rn,
            imm5 << 2,
        ),
        0b0111 => imm(if load { MemOp::Ldrb } else { MemOp::Strb }, rt, rn, imm5),
        0b1000 => imm(
            if load { MemOp::Ldrh } else { MemOp::Strh },
            rt,
            rn,
            imm5 << 1,
        ),
        _ => imm(
            if load { MemOp::Ldr } else { MemOp::Str },
            r3(hw, 8),
            13,
            (bits(hw, 7, 0) as u16) << 2,
        ),
    }
}

/// A5.2.5: miscellaneous 16-bit instructions.
fn misc(hw: u32, addr: u32) -> Insn {
    let (rd, rm) = (r3(hw, 0), r3(hw, 3));
    let op = bits(hw, 11, 5);
    let extend = |ext| Insn::Extend {
        ext,
        rd,
        rn: 15,
        rm,
        rot: 0,
    };
    match op {
        0b0000000..=0b0000011 => Insn::DpImm {
            op: DpOp::Add,
            s: Sf::No,
            rd: 13,
            rn: 13,
            carry: ImmCarry::Keep,
            imm: bits(hw, 6, 0) << 2,
        },
        0b0000100..=0b0000111 => Insn::DpImm {
            op: DpOp::Sub,
            s: Sf::No,
            rd: 13,
            rn: 13,
            carry: ImmCarry::Keep,
            imm: bits(hw, 6, 0) << 2,
        },
        _ if bits(hw, 10, 10) == 0 && bit(hw, 8) => Insn::Cbz {
            rn: rd,
            nonzero: bit(hw, 11),
            target: addr
                .wrapping_add(4)
                .wrapping_add(bits(hw, 9, 9) << 6 | bits(hw, 7, 3) << 1),
        },
        0b0010000 | 0b0010001 => extend(Ext::Sxth),
        0b0010010 | 0b0010011 => extend(Ext::Sxtb),
        0b0010100 | 0b0010101 => extend(Ext::Uxth),
        0b0010110 | 0b0010111 => extend(Ext::Uxtb),
        0b0100000..=0b0101111 => {
            let regs = (bits(hw, 7, 0) | bits(hw, 8, 8) << 14) as u16;
            if regs == 0 {
                return Insn::Undefined;
            }
            Insn::Multi {
                load: false,
                rn: 13,
                regs,
                wback: true,
                db: true,
            }
        }
        0b0110011 => {
            // CPS: bits 3 and 2 (A and a reserved bit) must be zero in ARMv7-M.
            if bits(hw, 3, 2) != 0 || bits(hw, 1, 0) == 0 {
                return Insn::Undefined;
            }
            Insn::Cps {
                disable: bit(hw, 4),
                primask: bit(hw, 1),
                faultmask: bit(hw, 0),
            }
        }
        0b1010000..=0b1010111 => {
            let rev = match bits(hw, 7, 6) {
                0 => Reverse::Rev,
                1 => Reverse::Rev16,
                3 => Reverse::Revsh,
                _ => return Insn::Undefined,
            };
            Insn::Rev { op: rev, rd, rm }
        }
        0b1100000..=0b1101111 => {
            let regs = (bits(hw, 7, 0) | bits(hw, 8, 8) << 15) as u16;
            if regs == 0 {
                return Insn::Undefined;
            }
            Insn::Multi {
                load: true,
                rn: 13,
                regs,
                wback: true,
                db: false,
            }
        }
        0b1110000..=0b1110111 => Insn::Bkpt {
            imm: bits(hw, 7, 0) as u8,
        },
        0b1111000..=0b1111111 => {
            let mask = bits(hw, 3, 0);
            let firstcond = bits(hw, 7, 4);
            if mask != 0 {
                if firstcond == 0b1111 || (firstcond == 0b1110 && mask.count_ones() != 1) {
                    return Insn::Undefined;
                }
                Insn::It {
                    state: bits(hw, 7, 0) as u8,
                }
            } else {
                match firstcond {
                    2 => Insn::Wfe,
                    3 => Insn::Wfi,
                    4 => Insn::Sev,
                    _ => Insn::Nop,
                }
            }
        }
        _ => Insn::Undefined,
    }
}
