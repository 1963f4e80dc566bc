//! The coprocessor space (A5.3.18) and the FPv4-SP encodings in it (A6): coprocessors 10
//! and 11 are the floating-point extension; any other coprocessor is absent (NOCP).
//! Double-precision forms (`sz == 1`) are UNDEFINED on a single-precision FPU.

use super::{bit, bits, reg};
use crate::insn::{Insn, VCvtInt, VOp, VUnary};

pub(super) fn decode(hw1: u32, hw2: u32) -> Insn {
    let coproc = bits(hw2, 11, 8);
    if coproc & 0b1110 != 0b1010 {
        return Insn::NoCoprocessor;
    }
    // The T bit (bit 12 of the first halfword) selects the unconditional space, which holds
    // no FPv4 instruction.
    if bit(hw1, 12) {
        return Insn::Undefined;
    }
    let op1 = bits(hw1, 9, 4);
    if op1 & 0b110000 == 0b100000 {
        if bit(hw2, 4) {
            transfer_32(hw1, hw2)
        } else {
            data_processing(hw1, hw2)
        }
    } else if op1 & 0b111110 == 0b000100 {
        transfer_64(hw1, hw2)
    } else if op1 & 0b100000 == 0 && op1 & 0b111010 != 0 {
        load_store(hw1, hw2)
    } else {
        Insn::Undefined
    }
}

/// S register number from a 4-bit field at `lo` and the extra bit `x` (Vd:D etc.).
fn sreg(v: u32, lo: u32, x: u32) -> u8 {
    ((bits(v, lo + 3, lo) << 1) | (x & 1)) as u8
}

/// D register number (D:Vd) as the index of its low S register.
fn dreg_as_s(v: u32, lo: u32, x: u32) -> u8 {
    (((x & 1) << 4 | bits(v, lo + 3, lo)) << 1) as u8
}

/// A6.4: floating-point data processing.
fn data_processing(hw1: u32, hw2: u32) -> Insn {
    if bit(hw2, 8) {
        return Insn::Undefined; // double precision
    }
    let sd = sreg(hw2, 12, bits(hw1, 6, 6));
    let sn = sreg(hw1, 0, bits(hw2, 7, 7));
    let sm = sreg(hw2, 0, bits(hw2, 5, 5));
    let opc1 = bits(hw1, 7, 7) << 2 | bits(hw1, 5, 4);
    let op6 = bit(hw2, 6);
    let arith = |op| Insn::VArith { op, sd, sn, sm };
    match opc1 {
        0b000 => arith(if op6 { VOp::Mls } else { VOp::Mla }),
        0b001 => arith(if op6 { VOp::Nmla } else { VOp::Nmls }),
        0b010 => arith(if op6 { VOp::Nmul } else { VOp::Mul }),
        0b011 => arith(if op6 { VOp::Sub } else { VOp::Add }),
        0b100 if !op6 => arith(VOp::Div),
        0b101 => arith(if op6 { VOp::Fnma } else { VOp::Fnms }),
        0b110 => arith(if op6 { VOp::Fms } else { VOp::Fma }),
        0b111 => other(hw1, hw2, sd, sm),
        _ => Insn::Undefined,
    }
}

/// A6.4 "other": VMOV immediate/register, VABS, VNEG, VSQRT, VCVT*, VCMP*.
fn other(hw1: u32, hw2: u32, sd: u8, sm: u8) -> Insn {
    let opc2 = bits(hw1, 3, 0);
    let opc3 = bits(hw2, 7, 6);
    if opc3 & 1 == 0 {
        if bits(hw2, 5, 4) != 0 {
            return Insn::Undefined;
        }
        return Insn::VMovImm {
            sd,
            imm: vfp_expand_imm(opc2 << 4 | bits(hw2, 3, 0)),
        };
    }
    let op7 = bit(hw2, 7);
    let unary = |op| Insn::VUnary { op, sd, sm };
    match opc2 {
        0b0000 => unary(if op7 { VUnary::Abs } else { VUnary::Mov }),
        0b0001 => unary(if op7 { VUnary::Sqrt } else { VUnary::Neg }),
        0b0010 | 0b0011 => Insn::VCvtHalf {
            sd,
            sm,
            to_half: opc2 == 0b0011,
            top: op7,
        },
        0b0100 => Insn::VCmp {
            sd,
            sm,
            zero: false,
            e: op7,
        },
        0b0101 => {
            if bits(hw2, 5, 5) != 0 || bits(hw2, 3, 0) != 0 {
                return Insn::Undefined;
            }
            Insn::VCmp {
                sd,
                sm: 0,
                zero: true,
                e: op7,
            }
        }
        0b1000 => Insn::VCvt {
            op: if op7 {
                VCvtInt::FromS32
            } else {
                VCvtInt::FromU32
            },
            sd,
            sm,
        },
        0b1100 => Insn::VCvt {
            op: VCvtInt::ToU32(op7),
            sd,
            sm,
        },
        0b1101 => Insn::VCvt {
            op: VCvtInt::ToS32(op7),
            sd,
            sm,
        },
        0b1010 | 0b1011 | 0b1110 | 0b1111 => {
            let half = !op7;
            let size = if half { 16 } else { 32 };
            let imm5 = (bits(hw2, 3, 0) << 1 | bits(hw2, 5, 5)) as u8;
            if u32::from(imm5) > size {
                return Insn::Undefined;
            }
            Insn::VCvtFixed {
                sd,
                to_fixed: bit(opc2, 2),
                unsigned: bit(opc2, 0),
                half,
                frac: size as u8 - imm5,
            }
        }
        _ => Insn::Undefined,
    }
}

/// `VFPExpandImm` for single precision: sign, 3-bit exponent, 4-bit fraction.
fn vfp_expand_imm(imm8: u32) -> u32 {
    let sign = bits(imm8, 7, 7) << 31;
    let b6 = bits(imm8, 6, 6);
    let exp = (b6 ^ 1) << 7 | (if b6 == 1 { 0b11111 } else { 0 }) << 2 | bits(imm8, 5, 4);
    sign | exp << 23 | bits(imm8, 3, 0) << 19
}

/// A6.7: 8, 16 and 32-bit transfers between core and extension registers.
fn transfer_32(hw1: u32, hw2: u32) -> Insn {
    let rt = reg(hw2, 12);
    let l = bit(hw1, 4);
    let a = bits(hw1, 7, 5);
    let c = bit(hw2, 8);
    if bits(hw2, 3, 0) != 0 {
        return Insn::Undefined;
    }
    match (c, a) {
        (false, 0b000) => {
            if rt == 13 || rt == 15 || bits(hw2, 6, 5) != 0 {
                return Insn::Undefined;
            }
            Insn::VMovCore {
                sn: sreg(hw1, 0, bits(hw2, 7, 7)),
                rt,
                to_core: l,
            }
        }
        (false, 0b111) => {
            if bits(hw1, 3, 0) != 0b0001 || bits(hw2, 7, 5) != 0 {
                return Insn::Undefined;
            }
            if l {
                if rt == 13 {
                    return Insn::Undefined;
                }
                Insn::Vmrs { rt }
            } else {
                if rt == 13 || rt == 15 {
                    return Insn::Undefined;
                }
                Insn::Vmsr { rt }
            }
        }
        (true, _) => {
            // VMOV between a core register and a 32-bit scalar Dd[x]: only opc1 = 0x and
            // opc2 = 00 exist without Advanced SIMD.
            let d = bits(hw2, 7, 7) << 4 | bits(hw1, 3, 0);
            if bit(hw1, 7) || bit(hw1, 6) || bits(hw2, 6, 5) != 0 || rt == 13 || rt == 15 || d >= 16
            {
                return Insn::Undefined;
            }
            Insn::VMovCore {
                sn: (d * 2 + bits(hw1, 5, 5)) as u8,
                rt,
                to_core: l,
            }
        }
        _ => Insn::Undefined,
    }
}

/// A6.8: 64-bit transfers between two core registers and two S or one D register.
fn transfer_64(hw1: u32, hw2: u32) -> Insn {
    let rt = reg(hw2, 12);
    let rt2 = reg(hw1, 0);
    let to_core = bit(hw1, 4);
    if bits(hw2, 7, 6) != 0 || !bit(hw2, 4) {
        return Insn::Undefined;
    }
    let sm = if bit(hw2, 8) {
        let m = dreg_as_s(hw2, 0, bits(hw2, 5, 5));
        if m >= 32 {
            return Insn::Undefined;
        }
        m
    } else {
        let m = sreg(hw2, 0, bits(hw2, 5, 5));
        if m == 31 {
            return Insn::Undefined;
        }
        m
    };
    let bad = |r: u8| r == 13 || r == 15;
    if bad(rt) || bad(rt2) || (to_core && rt == rt2) {
        return Insn::Undefined;
    }
    Insn::VMovPair {
        rt,
        rt2,
        sm,
        to_core,
    }
}

/// A6.5: extension register loads and stores.
fn load_store(hw1: u32, hw2: u32) -> Insn {
    let (p, u, w, l) = (bit(hw1, 8), bit(hw1, 7), bit(hw1, 5), bit(hw1, 4));
    let rn = reg(hw1, 0);
    let double = bit(hw2, 8);
    let imm8 = bits(hw2, 7, 0);
    let d_bit = bits(hw1, 6, 6);
    let sd = if double {
        dreg_as_s(hw2, 12, d_bit)
    } else {
        sreg(hw2, 12, d_bit)
    };
    let words = if double { 2 } else { 1 };
    if u32::from(sd) + words > 32 || (rn == 15 && !(l && p && !w)) {
        return Insn::Undefined;
    }
    if p && !w {
        // VLDR / VSTR
        return Insn::VMem {
            load: l,
            sd,
            rn,
            add: u,
            words: words as u8,
            imm: (imm8 << 2) as u16,
        };
    }
    if p == u {
        return Insn::Undefined;
    }
    if double && imm8 & 1 != 0 {
        return Insn::Undefined; // FLDMX/FSTMX
    }
    let count = imm8;
    if count == 0 || u32::from(sd) + count > 32 {
        return Insn::Undefined;
    }
    Insn::VMulti {
        load: l,
        sd,
        count: count as u8,
        rn,
        wback: w,
        db: p,
    }
}
