//! Decoding at the edges of the tables: encodings that must decode (including the
//! permanently undefined UDF, which is a defined instruction), ones that are UNDEFINED or
//! UNPREDICTABLE, and operand fields of a few tricky forms. Encodings from the ARMv7-M ARM.

use super::*;
use crate::insn::{Insn, VCvtInt};

fn d(hw1: u16, hw2: u16) -> Insn {
    decode(hw1, hw2, 0x1000).0
}

#[test]
fn defined_encodings() {
    let defined: &[(u16, u16, &str)] = &[
        (0xDE00, 0, "udf #0"),
        (0xF7F0, 0xA000, "udf.w #0"),
        (0xBF10, 0, "yield"),
        (0xF890, 0xF004, "pld [r0, #4]"),
        (0xEE00, 0x0B10, "vmov.32 d0[0], r0"),
        (0xEE3F, 0x1B10, "vmov.32 r1, d15[1]"),
        (0xEEF1, 0xFA10, "vmrs APSR_nzcv, fpscr"),
        (0xF321, 0x000F, "ssat16 r0, #16, r1"),
        (0xEEB2, 0x0AE0, "vcvtt.f32.f16 s0, s1"),
        (0xFBD2, 0x01D3, "smlsldx r0, r1, r2, r3"),
        (0xFBE2, 0x0163, "umaal r0, r1, r2, r3"),
        (0xE8DF, 0xF010, "tbh [pc, r0, lsl #1]"),
        (0xE8D1, 0x0F5F, "ldrexh r0, [r1]"),
        (0xE8C1, 0x0F42, "strexb r2, r0, [r1]"),
        (0xEAC1, 0x0022, "pkhtb r0, r1, r2, asr #32"),
        (0xF3EF, 0x8012, "mrs r0, basepri_max"),
        (0xF380, 0x8813, "msr faultmask, r0"),
        (0xB671, 0, "cpsid f"),
        (0xFAA1, 0xF082, "sel r0, r1, r2"),
        (0xFB61, 0x3012, "smmlsr r0, r1, r2, r3"),
        (0xEE90, 0x0A81, "vfnms.f32 s0, s1, s2"),
        (0xEEBF, 0x0A40, "vcvt.u16.f32 s0, s0, #16"),
    ];
    for &(hw1, hw2, asm) in defined {
        let (ok, len) = is_defined(hw1, hw2);
        assert!(ok, "{asm} ({hw1:04x} {hw2:04x}) must decode");
        assert_eq!(len, if is_32bit(hw1) { 4 } else { 2 }, "{asm}");
    }
}

#[test]
fn undefined_and_unpredictable_encodings() {
    let undefined: &[(u16, u16, &str)] = &[
        (0xEE30, 0x0B01, "vadd.f64: no double precision on FPv4-SP"),
        (0xF000, 0xC000, "blx (immediate): no ARM state in ARMv7-M"),
        (0xE8BD, 0xC000, "ldm sp!, {lr, pc}: PC and LR both"),
        (0xE8BD, 0x0001, "ldm sp!, {r0}: fewer than two registers"),
        (0xE92D, 0x8001, "stmdb sp!, {r0, pc}: PC stored"),
        (
            0xEB0D,
            0x1D01,
            "add.w sp, sp, r1, lsl #4: SP with a shift over 3",
        ),
        (0xEA4F, 0x0D0D, "mov.w sp, sp"),
        (0xFB81, 0x0002, "smull r0, r0, r1, r2: RdLo == RdHi"),
        (0xBFF8, 0, "it with firstcond 0b1111"),
        (0xBA80, 0, "rev with op 0b10"),
        (0xE850, 0xDF00, "ldrex sp, [r0]"),
        (0x44FF, 0, "add pc, pc"),
    ];
    for &(hw1, hw2, why) in undefined {
        assert_eq!(d(hw1, hw2), Insn::Undefined, "{why} ({hw1:04x} {hw2:04x})");
    }
}

#[test]
fn coprocessors_other_than_the_fpu_are_absent() {
    // mrc p15, 0, r0, c1, c0, 0
    assert_eq!(d(0xEE11, 0x0F10), Insn::NoCoprocessor);
}

#[test]
fn pc_relative_operands_are_resolved() {
    // ldr r0, [pc, #8] at 0x1002: Align(0x1006, 4) + 8.
    assert_eq!(
        decode(0x4802, 0, 0x1002).0,
        Insn::MemLit {
            op: crate::insn::MemOp::Ldr,
            rt: 0,
            addr: 0x100C
        }
    );
    // b.w with a negative offset: 0xF7FF 0xBFFE is `b .` (offset -4).
    assert_eq!(decode(0xF7FF, 0xBFFE, 0x2000).0, Insn::B { target: 0x2000 });
    // bl +4096
    assert_eq!(
        decode(0xF001, 0xF800, 0x2000).0,
        Insn::Bl { target: 0x3004 }
    );
}

#[test]
fn modified_immediates() {
    use crate::insn::ImmCarry;
    assert_eq!(thumb_expand_imm(0x0AB), Some((0xAB, ImmCarry::Keep)));
    assert_eq!(thumb_expand_imm(0x1AB), Some((0x00AB_00AB, ImmCarry::Keep)));
    assert_eq!(thumb_expand_imm(0x2AB), Some((0xAB00_AB00, ImmCarry::Keep)));
    assert_eq!(thumb_expand_imm(0x3AB), Some((0xABAB_ABAB, ImmCarry::Keep)));
    assert_eq!(thumb_expand_imm(0x100), None);
    // Rotation 8: 0x80 | 0x7F rotated right by 8.
    assert_eq!(
        thumb_expand_imm(0x47F),
        Some((0xFF00_0000, ImmCarry::Bit31))
    );
}

#[test]
fn vfp_conversions_decode_their_direction_and_rounding() {
    // vcvt.s32.f32 s0, s1 (round toward zero) and vcvtr.s32.f32 s0, s1.
    assert_eq!(
        d(0xEEBD, 0x0AE0),
        Insn::VCvt {
            op: VCvtInt::ToS32(true),
            sd: 0,
            sm: 1
        }
    );
    assert_eq!(
        d(0xEEBD, 0x0A60),
        Insn::VCvt {
            op: VCvtInt::ToS32(false),
            sd: 0,
            sm: 1
        }
    );
    // vmov.f32 s0, #1.0 expands to 0x3F80_0000.
    assert_eq!(
        d(0xEEB7, 0x0A00),
        Insn::VMovImm {
            sd: 0,
            imm: 0x3F80_0000
        }
    );
}
