//! The 32-bit load and store encodings (A5.3.5–A5.3.10).

use super::{bit, bits, pc_aligned, reg};
use crate::insn::{Index, Insn, MemOp};

/// A5.3.5: LDM, STM, PUSH, POP (32-bit).
pub(super) fn load_store_multiple(hw1: u32, hw2: u32) -> Insn {
    let rn = reg(hw1, 0);
    let wback = bit(hw1, 5);
    let load = bit(hw1, 4);
    let regs = hw2 as u16;
    let db = match bits(hw1, 8, 7) {
        0b01 => false,
        0b10 => true,
        _ => return Insn::Undefined,
    };
    let (p, m) = (bit(hw2, 15), bit(hw2, 14));
    let bad = rn == 15
        || regs.count_ones() < 2
        || bit(hw2, 13)
        || (wback && regs & (1 << rn) != 0)
        || if load { p && m } else { p };
    if bad {
        return Insn::Undefined;
    }
    Insn::Multi {
        load,
        rn,
        regs,
        wback,
        db,
    }
}

/// A5.3.6: LDRD/STRD, the exclusives and TBB/TBH.
pub(super) fn dual_exclusive_table(hw1: u32, hw2: u32, addr: u32) -> Insn {
    let rn = reg(hw1, 0);
    let (rt, rt2_or_rd) = (reg(hw2, 12), reg(hw2, 8));
    let op1 = bits(hw1, 8, 7);
    let op2 = bits(hw1, 5, 4);
    let imm8 = (bits(hw2, 7, 0) as u16) << 2;
    let sp_or_pc = |r: u8| r == 13 || r == 15;
    if op1 & 0b10 != 0 || op2 & 0b10 != 0 {
        let (p, u, w, load) = (bit(hw1, 8), bit(hw1, 7), bit(hw1, 5), bit(hw1, 4));
        let rt2 = rt2_or_rd;
        if load && rn == 15 {
            if sp_or_pc(rt) || sp_or_pc(rt2) || rt == rt2 || w {
                return Insn::Undefined;
            }
            let base = pc_aligned(addr);
            let addr = if u {
                base.wrapping_add(imm8.into())
            } else {
                base.wrapping_sub(imm8.into())
            };
            return Insn::Dual64Lit { rt, rt2, addr };
        }
        let index = match (p, w) {
            (true, false) => Index::Offset,
            (true, true) => Index::Pre,
            _ => Index::Post,
        };
        let bad = (w && (rn == rt || rn == rt2))
            || sp_or_pc(rt)
            || sp_or_pc(rt2)
            || (load && rt == rt2)
            || (!load && rn == 15);
        if bad {
            return Insn::Undefined;
        }
        return Insn::Dual64 {
            load,
            rt,
            rt2,
            rn,
            index,
            add: u,
            imm: imm8,
        };
    }
    let op3 = bits(hw2, 7, 4);
    match (op1, op2) {
        (0b00, 0b00) => {
            let rd = rt2_or_rd;
            if sp_or_pc(rd) || sp_or_pc(rt) || rn == 15 || rd == rn || rd == rt {
                return Insn::Undefined;
            }
            Insn::Strex {
                rd,
                rt,
                rn,
                imm: imm8,
                bytes: 4,
            }
        }
        (0b00, 0b01) => {
            if sp_or_pc(rt) || rn == 15 || bits(hw2, 11, 8) != 0b1111 {
                return Insn::Undefined;
            }
            Insn::Ldrex {
                rt,
                rn,
                imm: imm8,
                bytes: 4,
            }
        }
        (0b01, 0b00) => {
            let rd = bits(hw2, 3, 0) as u8;
            let bytes = match op3 {
                0b0100 => 1,
                0b0101 => 2,
                _ => return Insn::Undefined,
            };
            if sp_or_pc(rd) || sp_or_pc(rt) || rn == 15 || rd == rn || rd == rt {
                return Insn::Undefined;
            }
            Insn::Strex {
                rd,
                rt,
                rn,
                imm: 0,
                bytes,
            }
        }
        (0b01, 0b01) => match op3 {
            0b0000 | 0b0001 => {
                let rm = bits(hw2, 3, 0) as u8;
                if rn == 13 || sp_or_pc(rm) || bits(hw2, 15, 8) != 0b1111_0000 {
                    return Insn::Undefined;
                }
                Insn::Tbb {
                    rn,
                    rm,
                    half: op3 == 1,
                }
            }
            0b0100 | 0b0101 => {
                if sp_or_pc(rt) || rn == 15 {
                    return Insn::Undefined;
                }
                Insn::Ldrex {
                    rt,
                    rn,
                    imm: 0,
                    bytes: if op3 == 0b0100 { 1 } else { 2 },
                }
            }
            _ => Insn::Undefined,
        },
        _ => Insn::Undefined,
    }
}

/// The immediate and register forms shared by loads and stores once their `MemOp` is
/// known: `imm12` (op1 bit 0 set), the `PUW` imm8 forms, and the register offset.
fn single(op: MemOp, hw1: u32, hw2: u32, addr: u32) -> Insn {
    let rn = reg(hw1, 0);
    let rt = reg(hw2, 12);
    let store = op.is_store();
    if rn == 15 {
        if store {
            return Insn::Undefined;
        }
        let imm12 = bits(hw2, 11, 0);
        let base = pc_aligned(addr);
        let addr = if bit(hw1, 7) {
            base.wrapping_add(imm12)
        } else {
            base.wrapping_sub(imm12)
        };
        return checked(op, rt, Insn::MemLit { op, rt, addr });
    }
    if bit(hw1, 7) {
        let insn = Insn::MemImm {
            op,
            rt,
            rn,
            index: Index::Offset,
            add: true,
            user: false,
            imm: bits(hw2, 11, 0) as u16,
        };
        return checked(op, rt, insn);
    }
    if bit(hw2, 11) {
        let (p, u, w) = (bit(hw2, 10), bit(hw2, 9), bit(hw2, 8));
        let user = p && u && !w;
        let index = match (p, w) {
            (true, false) => Index::Offset,
            (true, true) => Index::Pre,
            (false, true) => Index::Post,
            (false, false) => return Insn::Undefined,
        };
        if user && (rt == 13 || rt == 15) {
            return Insn::Undefined;
        }
        if index != Index::Offset && rn == rt {
            return Insn::Undefined;
        }
        let insn = Insn::MemImm {
            op,
            rt,
            rn,
            index,
            add: u,
            user,
            imm: bits(hw2, 7, 0) as u16,
        };
        return checked(op, rt, insn);
    }
    if bits(hw2, 11, 6) != 0 {
        return Insn::Undefined;
    }
    let rm = reg(hw2, 0);
    if rm == 13 || rm == 15 {
        return Insn::Undefined;
    }
    checked(
        op,
        rt,
        Insn::MemReg {
            op,
            rt,
            rn,
            rm,
            amount: bits(hw2, 5, 4) as u8,
        },
    )
}

/// Rt constraints: PC only as the destination of a word load (a branch), SP never for the
/// byte and halfword forms, and not for a store of PC.
fn checked(op: MemOp, rt: u8, insn: Insn) -> Insn {
    let ok = match op {
        MemOp::Ldr => true,
        MemOp::Str => rt != 15,
        _ => rt != 13 && rt != 15,
    };
    if ok { insn } else { Insn::Undefined }
}

/// A5.3.10: STR, STRH, STRB (32-bit).
pub(super) fn store_single(hw1: u32, hw2: u32) -> Insn {
    let op = match bits(hw1, 6, 5) {
        0b00 => MemOp::Strb,
        0b01 => MemOp::Strh,
        0b10 => MemOp::Str,
        _ => return Insn::Undefined,
    };
    single(op, hw1, hw2, 0)
}

/// A5.3.9: LDRB, LDRSB and the preload hints.
pub(super) fn load_byte(hw1: u32, hw2: u32, addr: u32) -> Insn {
    let signed = bit(hw1, 8);
    if reg(hw2, 12) == 15 {
        return hint(hw1, hw2);
    }
    single(
        if signed { MemOp::Ldrsb } else { MemOp::Ldrb },
        hw1,
        hw2,
        addr,
    )
}

/// A5.3.8: LDRH, LDRSH and the unallocated hints.
pub(super) fn load_half(hw1: u32, hw2: u32, addr: u32) -> Insn {
    let signed = bit(hw1, 8);
    if reg(hw2, 12) == 15 {
        return hint(hw1, hw2);
    }
    single(
        if signed { MemOp::Ldrsh } else { MemOp::Ldrh },
        hw1,
        hw2,
        addr,
    )
}

/// The Rt == PC forms of the byte and halfword loads are preloads or unallocated hints:
/// they execute as NOPs, except the writeback/unprivileged forms, which are UNPREDICTABLE.
fn hint(hw1: u32, hw2: u32) -> Insn {
    let rn = reg(hw1, 0);
    if rn == 15 || bit(hw1, 7) {
        return Insn::Nop;
    }
    if bits(hw2, 11, 8) == 0b1100 || bits(hw2, 11, 6) == 0 {
        return Insn::Nop;
    }
    Insn::Undefined
}

/// A5.3.7: LDR (32-bit), including POP of one register.
pub(super) fn load_word(hw1: u32, hw2: u32, addr: u32) -> Insn {
    if bit(hw1, 8) {
        return Insn::Undefined;
    }
    single(MemOp::Ldr, hw1, hw2, addr)
}
