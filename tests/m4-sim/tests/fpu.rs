//! FPv4-SP through its instructions: arithmetic, the fused and unfused multiply-accumulates,
//! conversions with their rounding and saturation, half precision, compares into the APSR,
//! the VMOV forms, loads and stores, FPSCR modes (FZ, DN, rounding) and the access check
//! (CPACR). Expected values from the ARMv7-M ARM's pseudocode.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

mod common;
use common::*;
use m4_sim::Reg;

const IOC: u32 = 1;
const DZC: u32 = 2;
const UFC: u32 = 8;
const IXC: u32 = 16;
const IDC: u32 = 128;
const FZ: u32 = 1 << 24;
const DN: u32 = 1 << 25;
const RM: u32 = 2 << 22;

/// A rig with CP10/CP11 enabled (as cortex-m-rt does for a hard-float image).
fn fpu(code: &[u16]) -> Rig {
    let mut rig = Rig::new(code);
    rig.scs_write(0xE000_ED88, 0xF << 20);
    rig
}

/// Sets FPSCR inside an active FP context (CONTROL.FPCA), so the first FP instruction
/// does not replace its modes with FPDSCR's.
fn set_fpscr(rig: &mut Rig, v: u32) {
    rig.cpu.write_reg(Reg::Control, 4);
    rig.cpu.write_reg(Reg::Fpscr, v);
}

fn fpscr(rig: &Rig) -> u32 {
    rig.cpu.read_reg(Reg::Fpscr)
}

#[test]
fn arithmetic() {
    const CODE: &[u16] = &[
        // asm: arith
        0xEE30, 0x1A20, // 00: vadd.f32 s2, s0, s1
        0xEE70, 0x1A60, // 04: vsub.f32 s3, s0, s1
        0xEE20, 0x2A20, // 08: vmul.f32 s4, s0, s1
        0xEEC0, 0x2A20, // 0c: vdiv.f32 s5, s0, s1
        0xEEB1, 0x3AC0, // 10: vsqrt.f32 s6, s0
        0xEE60, 0x3A60, // 14: vnmul.f32 s7, s0, s1
        0xEEB0, 0x4AE0, // 18: vabs.f32 s8, s1
        0xEEF1, 0x4A40, // 1c: vneg.f32 s9, s0
    ];
    let mut rig = fpu(CODE);
    rig.set_f(0, 2.0);
    rig.set_f(1, -0.5);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.f(2), 1.5);
    assert_eq!(rig.f(3), 2.5);
    assert_eq!(rig.f(4), -1.0);
    assert_eq!(rig.f(5), -4.0);
    assert_eq!(rig.f(6), 2f32.sqrt());
    assert_eq!(rig.f(7), 1.0);
    assert_eq!(rig.f(8), 0.5);
    assert_eq!(rig.f(9), -2.0);
    // √2 is inexact; everything else was exact.
    assert_eq!(fpscr(&rig), IXC);
}

#[test]
fn division_by_zero_and_invalid_operations() {
    const CODE: &[u16] = &[
        // asm: arith
        0xEE30, 0x1A20, // 00: vadd.f32 s2, s0, s1
        0xEE70, 0x1A60, // 04: vsub.f32 s3, s0, s1
        0xEE20, 0x2A20, // 08: vmul.f32 s4, s0, s1
        0xEEC0, 0x2A20, // 0c: vdiv.f32 s5, s0, s1
        0xEEB1, 0x3AC0, // 10: vsqrt.f32 s6, s0
        0xEE60, 0x3A60, // 14: vnmul.f32 s7, s0, s1
        0xEEB0, 0x4AE0, // 18: vabs.f32 s8, s1
        0xEEF1, 0x4A40, // 1c: vneg.f32 s9, s0
    ];
    let mut rig = fpu(CODE);
    rig.set_f(0, -1.0);
    rig.set_f(1, 0.0);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.f(5), f32::NEG_INFINITY);
    assert_eq!(rig.s(6), 0x7FC0_0000, "√-1 is the default NaN");
    assert_eq!(fpscr(&rig), DZC | IOC);
}

#[test]
fn fused_multiply_add_rounds_once() {
    const CODE: &[u16] = &[
        // asm: mla_fma
        0xEEB0, 0x2A41, // 00: vmov.f32 s4, s2
        0xEE00, 0x1A20, // 04: vmla.f32 s2, s0, s1
        0xEEA0, 0x2A20, // 08: vfma.f32 s4, s0, s1
    ];
    // (1 + 2^-12)² = 1 + 2^-11 + 2^-24: the product alone rounds (to even) to 1 + 2^-11.
    let mut rig = fpu(CODE);
    let a = f32::from_bits(0x3F80_0800);
    rig.set_f(0, a);
    rig.set_f(1, a);
    rig.set_f(2, -f32::from_bits(0x3F80_1000));
    rig.run_to_end(CODE.len());
    assert_eq!(rig.s(2), 0, "VMLA: rounded product minus itself");
    assert_eq!(rig.f(4), 2f32.powi(-24), "VFMA keeps the 2^-24");
}

#[test]
fn the_multiply_accumulate_family_negates_as_specified() {
    const CODE: &[u16] = &[
        // asm: mac_family
        0xEEB0, 0x5A41, // 00: vmov.f32 s10, s2
        0xEEF0, 0x5A41, // 04: vmov.f32 s11, s2
        0xEEB0, 0x6A41, // 08: vmov.f32 s12, s2
        0xEEF0, 0x6A41, // 0c: vmov.f32 s13, s2
        0xEEB0, 0x7A41, // 10: vmov.f32 s14, s2
        0xEEF0, 0x7A41, // 14: vmov.f32 s15, s2
        0xEE00, 0x5A60, // 18: vmls.f32 s10, s0, s1
        0xEE50, 0x5A60, // 1c: vnmla.f32 s11, s0, s1
        0xEE10, 0x6A20, // 20: vnmls.f32 s12, s0, s1
        0xEEE0, 0x6A60, // 24: vfms.f32 s13, s0, s1
        0xEE90, 0x7A60, // 28: vfnma.f32 s14, s0, s1
        0xEED0, 0x7A20, // 2c: vfnms.f32 s15, s0, s1
    ];
    let mut rig = fpu(CODE);
    rig.set_f(0, 3.0);
    rig.set_f(1, 4.0);
    rig.set_f(2, 100.0);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.f(10), 88.0, "VMLS: d - n*m");
    assert_eq!(rig.f(11), -112.0, "VNMLA: -d - n*m");
    assert_eq!(rig.f(12), -88.0, "VNMLS: -d + n*m");
    assert_eq!(rig.f(13), 88.0, "VFMS: d - n*m");
    assert_eq!(rig.f(14), -112.0, "VFNMA: -d - n*m");
    assert_eq!(rig.f(15), -88.0, "VFNMS: -d + n*m");
}

/// S1–S4 after VCVT/VCVTR to s32 and u32 of `v` under `mode`, and the flags.
fn to_int(v: f32, mode: u32) -> ([u32; 4], u32) {
    const CODE: &[u16] = &[
        // asm: cvt_int
        0xEEFD, 0x0AC0, // 00: vcvt.s32.f32 s1, s0
        0xEEBD, 0x1A40, // 04: vcvtr.s32.f32 s2, s0
        0xEEFC, 0x1AC0, // 08: vcvt.u32.f32 s3, s0
        0xEEBC, 0x2A40, // 0c: vcvtr.u32.f32 s4, s0
    ];
    let mut rig = fpu(CODE);
    rig.set_f(0, v);
    set_fpscr(&mut rig, mode);
    rig.run_to_end(CODE.len());
    ([rig.s(1), rig.s(2), rig.s(3), rig.s(4)], fpscr(&rig) & 0xFF)
}

#[test]
fn conversions_to_integer_round_and_saturate() {
    let neg = |v: i32| v as u32;
    // VCVT rounds toward zero; VCVTR uses FPSCR (nearest, ties to even).
    assert_eq!(to_int(2.5, 0), ([2, 2, 2, 2], IXC));
    assert_eq!(to_int(3.5, 0).0, [3, 4, 3, 4]);
    assert_eq!(to_int(-2.5, 0), ([neg(-2), neg(-2), 0, 0], IXC | IOC));
    assert_eq!(to_int(-2.5, RM).0, [neg(-2), neg(-3), 0, 0]);
    assert_eq!(
        to_int(4.5e9, 0),
        ([0x7FFF_FFFF, 0x7FFF_FFFF, 0xFFFF_FFFF, 0xFFFF_FFFF], IOC)
    );
    assert_eq!(to_int(-0.25, 0), ([0, 0, 0, 0], IXC));
    assert_eq!(to_int(f32::NAN, 0), ([0, 0, 0, 0], IOC));
    assert_eq!(to_int(-3e9, 0).0, [0x8000_0000, 0x8000_0000, 0, 0]);
}

#[test]
fn conversions_from_integer_use_the_rounding_mode() {
    const CODE: &[u16] = &[
        // asm: cvt_from_int
        0xEEF8, 0x0AC0, // 00: vcvt.f32.s32 s1, s0
        0xEEB8, 0x1A40, // 04: vcvt.f32.u32 s2, s0
    ];
    let mut rig = fpu(CODE);
    rig.set_s(0, 0xFFFF_FFFF);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.f(1), -1.0);
    assert_eq!(rig.f(2), 4_294_967_296.0);
    assert_eq!(fpscr(&rig), IXC);
    let mut rig = fpu(CODE);
    rig.set_s(0, 0x0100_0001); // 2^24 + 1: a tie, to even below
    set_fpscr(&mut rig, RM);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.f(1), 16_777_216.0);
}

#[test]
fn fixed_point_conversions() {
    const CODE: &[u16] = &[
        // asm: cvt_fixed
        0xEEBE, 0x0A44, // 00: vcvt.s16.f32 s0, s0, #8
        0xEEFB, 0x0AC8, // 04: vcvt.f32.u32 s1, s1, #16
    ];
    let mut rig = fpu(CODE);
    rig.set_f(0, -1.5);
    rig.set_s(1, 0x0003_8000); // 3.5 in 16.16
    rig.run_to_end(CODE.len());
    assert_eq!(rig.s(0), (-384i32) as u32, "sign-extended 16-bit result");
    assert_eq!(rig.f(1), 3.5);
}

#[test]
fn half_precision_conversions() {
    const CODE: &[u16] = &[
        // asm: cvt_half
        0xEEF3, 0x0A40, // 00: vcvtb.f16.f32 s1, s0
        0xEEF3, 0x0AC1, // 04: vcvtt.f16.f32 s1, s2
        0xEEF2, 0x1A60, // 08: vcvtb.f32.f16 s3, s1
        0xEEB2, 0x2AE0, // 0c: vcvtt.f32.f16 s4, s1
    ];
    let mut rig = fpu(CODE);
    rig.set_f(0, 1.0);
    rig.set_f(2, -65504.0);
    rig.set_s(1, 0);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.s(1), 0xFBFF_3C00);
    assert_eq!(rig.f(3), 1.0);
    assert_eq!(rig.f(4), -65504.0);
    // Too large for half: infinity (IEEE) or, with AHP, the largest value and Invalid.
    let mut rig = fpu(CODE);
    rig.set_f(0, 1e6);
    rig.set_f(2, 1e6);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.s(1) & 0xFFFF, 0x7C00);
    assert_eq!(fpscr(&rig) & 0xFF, OFC_IXC);
    let mut rig = fpu(CODE);
    rig.set_f(0, 1e6);
    rig.set_f(2, 1.0);
    set_fpscr(&mut rig, 1 << 26);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.s(1) & 0xFFFF, 0x7FFF);
    assert_eq!(
        rig.f(3),
        131_008.0,
        "AHP has no infinity: exponent 31 is a number"
    );
    assert_eq!(fpscr(&rig) & 0xFF, IOC);
}

const OFC_IXC: u32 = 4 | IXC;

#[test]
fn compares_reach_the_apsr() {
    const CODE: &[u16] = &[
        // asm: cmp
        0xEEB4, 0x0A60, // 00: vcmp.f32 s0, s1
        0xEEF1, 0xFA10, // 04: vmrs APSR_nzcv, fpscr
        0xBFCC, // 08: ite gt
        0x2001, // 0a: movgt r0, #0x1
        0x2002, // 0c: movle r0, #0x2
        0xEEB5, 0x0AC0, // 0e: vcmpe.f32 s0, #0
        0xEEF1, 0x1A10, // 12: vmrs r1, fpscr
    ];
    let run = |a: f32, b: f32| {
        let mut rig = fpu(CODE);
        rig.set_f(0, a);
        rig.set_f(1, b);
        rig.run_to_end(CODE.len());
        (rig.r(0), rig.r(1) >> 28, rig.r(1) & 0xFF)
    };
    assert_eq!(run(2.0, 1.0), (1, 0b0010, 0));
    assert_eq!(run(1.0, 2.0), (2, 0b0010, 0));
    assert_eq!(run(-0.0, 0.0), (2, 0b0110, 0));
    assert_eq!(run(-1.0, 0.0), (2, 0b1000, 0));
    // Unordered: GT fails; VCMPE of a quiet NaN signals Invalid, VCMP does not.
    assert_eq!(run(f32::NAN, 1.0), (2, 0b0011, IOC));
}

#[test]
fn moves_between_core_and_fp_registers() {
    const CODE: &[u16] = &[
        // asm: vmov_forms
        0xEE00, 0x0A10, // 00: vmov s0, r0
        0xEE10, 0x1A10, // 04: vmov r1, s0
        0xEC43, 0x2A11, // 08: vmov s2, s3, r2, r3
        0xEC55, 0x4B11, // 0c: vmov r4, r5, d1
        0xEEB7, 0x2A08, // 10: vmov.f32 s4, #1.500000e+00
        0xEEFC, 0x2A00, // 14: vmov.f32 s5, #-1.250000e-01
        0xEC42, 0x0B13, // 18: vmov d3, r0, r2
        0xEE33, 0x6B10, // 1c: vmov.32 r6, d3[1]
        0xEE04, 0x3B10, // 20: vmov.32 d4[0], r3
    ];
    let mut rig = fpu(CODE);
    rig.set(0, 0x1111_1111);
    rig.set(2, 0x2222_2222);
    rig.set(3, 0x3333_3333);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.s(0), 0x1111_1111);
    assert_eq!(rig.r(1), 0x1111_1111);
    assert_eq!((rig.s(2), rig.s(3)), (0x2222_2222, 0x3333_3333));
    assert_eq!((rig.r(4), rig.r(5)), (0x2222_2222, 0x3333_3333));
    assert_eq!(rig.f(4), 1.5);
    assert_eq!(rig.f(5), -0.125);
    assert_eq!((rig.s(6), rig.s(7)), (0x1111_1111, 0x2222_2222));
    assert_eq!(rig.r(6), 0x2222_2222);
    assert_eq!(rig.s(8), 0x3333_3333);
}

#[test]
fn loads_stores_and_the_fp_stack() {
    const CODE: &[u16] = &[
        // asm: load_store
        0xED90, 0x0A00, // 00: vldr s0, [r0]
        0xED90, 0x1B01, // 04: vldr d1, [r0, #4]
        0xED80, 0x0A04, // 08: vstr s0, [r0, #16]
        0xECA0, 0x0A03, // 0c: vstmia r0!, {s0, s1, s2}
        0xED30, 0x2A03, // 10: vldmdb r0!, {s4, s5, s6}
        0xED2D, 0x1B02, // 14: vpush {d1}
        0xECBD, 0x4A02, // 18: vpop {s8, s9}
    ];
    let mut rig = fpu(CODE);
    for i in 0..4 {
        rig.poke(DATA + 4 * i, 0xA000_0000 + i);
    }
    rig.set(0, DATA);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.s(0), 0xA000_0000);
    assert_eq!((rig.s(2), rig.s(3)), (0xA000_0001, 0xA000_0002));
    assert_eq!(rig.word(DATA + 16), 0xA000_0000);
    assert_eq!(rig.r(0), DATA);
    // S0–S2 went out (S1 was never loaded: 0) and came back as S4–S6.
    assert_eq!(
        (rig.s(4), rig.s(5), rig.s(6)),
        (0xA000_0000, 0, 0xA000_0001)
    );
    assert_eq!((rig.s(8), rig.s(9)), (0xA000_0001, 0xA000_0002));
    assert_eq!(rig.r(13), STACK);
}

/// S2 and the FPSCR after `vadd s2, s0, s1` with the FPSCR set to `mode`.
fn add_with(mode: u32, a: u32, b: u32) -> (u32, u32) {
    const CODE: &[u16] = &[
        // asm: fpscr_rw
        0xEEE1, 0x0A10, // 00: vmsr fpscr, r0
        0xEE30, 0x1A20, // 04: vadd.f32 s2, s0, s1
        0xEEF1, 0x1A10, // 08: vmrs r1, fpscr
    ];
    let mut rig = fpu(CODE);
    rig.set(0, mode);
    rig.set_s(0, a);
    rig.set_s(1, b);
    rig.run_to_end(CODE.len());
    (rig.s(2), rig.r(1))
}

#[test]
fn flush_to_zero_and_default_nan() {
    let denormal = 0x0000_0001;
    // Without FZ the denormal adds exactly.
    assert_eq!(add_with(0, denormal, denormal), (2, 0));
    // FZ flushes inputs (IDC) ...
    assert_eq!(add_with(FZ, denormal, 0x3F80_0000), (0x3F80_0000, FZ | IDC));
    // ... and tiny results (UFC, not IXC).
    assert_eq!(add_with(FZ, 0x0080_0001, 0x8080_0000), (0, FZ | UFC));
    // A signalling NaN is quietened (Invalid), or replaced by the default NaN with DN.
    assert_eq!(add_with(0, 0x7F80_0001, 0x3F80_0000), (0x7FC0_0001, IOC));
    assert_eq!(
        add_with(DN, 0xFF80_0001, 0x3F80_0000),
        (0x7FC0_0000, DN | IOC)
    );
    // x - x is +0 except rounding toward minus infinity.
    assert_eq!(add_with(0, 0x3F80_0000, 0xBF80_0000).0, 0);
    assert_eq!(add_with(RM, 0x3F80_0000, 0xBF80_0000).0, 0x8000_0000);
    // Overflow: to infinity when rounding to nearest, to the largest value toward zero.
    assert_eq!(
        add_with(0, 0x7F7F_FFFF, 0x7F7F_FFFF),
        (0x7F80_0000, 4 | IXC)
    );
    assert_eq!(add_with(3 << 22, 0x7F7F_FFFF, 0x7F7F_FFFF).0, 0x7F7F_FFFF);
}

#[test]
fn fp_instructions_fault_until_the_coprocessor_is_enabled() {
    const CODE: &[u16] = &[
        // asm: vadd_only
        0xEE30, 0x1A20, // 00: vadd.f32 s2, s0, s1
    ];
    let mut rig = Rig::new(CODE);
    rig.scs_write(0xE000_ED24, 1 << 18);
    rig.run_to_handler(6);
    assert_eq!(rig.scs_read(0xE000_ED28), 1 << 19, "UFSR.NOCP");
}

#[test]
fn the_first_fp_instruction_starts_an_fp_context_from_fpdscr() {
    const CODE: &[u16] = &[
        // asm: vadd_only
        0xEE30, 0x1A20, // 00: vadd.f32 s2, s0, s1
    ];
    let mut rig = fpu(CODE);
    rig.scs_write(0xE000_EF3C, FZ | DN);
    rig.cpu.write_reg(Reg::Fpscr, 0);
    assert_eq!(rig.cpu.read_reg(Reg::Control) & 4, 0);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.cpu.read_reg(Reg::Control) & 4, 4, "CONTROL.FPCA");
    assert_eq!(fpscr(&rig), FZ | DN);
}
