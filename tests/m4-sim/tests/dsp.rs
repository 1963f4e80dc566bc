//! The DSP extension: saturation and the Q flag, parallel arithmetic and the GE flags,
//! SEL, the halfword and most-significant-word multiplies, packing, extension, USAD8.
//! Expected values are worked from the ARMv7-M ARM's pseudocode.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

mod common;
use common::*;

fn run(code: &[u16], regs: &[(u8, u32)]) -> Rig {
    let mut rig = Rig::new(code);
    for &(r, v) in regs {
        rig.set(r, v);
    }
    rig.run_to_end(code.len());
    rig
}

/// R2 (and the Q flag) after `code` with R0, R1 (and R3, R4 as accumulators).
fn r2(code: &[u16], r0: u32, r1: u32) -> (u32, bool) {
    let rig = run(code, &[(0, r0), (1, r1), (3, 0), (4, 0)]);
    (rig.r(2), rig.q())
}

#[test]
fn saturating_add_and_subtract_set_q() {
    const QADD: &[u16] = &[
        // asm: qadd
        0xFA81, 0xF280, // 00: qadd r2, r0, r1
    ];
    assert_eq!(r2(QADD, 0x7FFF_FFFF, 1), (0x7FFF_FFFF, true));
    assert_eq!(r2(QADD, 5, (-7i32) as u32), ((-2i32) as u32, false));
    const QSUB: &[u16] = &[
        // asm: qsub
        0xFA81, 0xF2A0, // 00: qsub r2, r0, r1
    ];
    // QSUB Rd, Rm, Rn: Rm - Rn, here R0 - R1.
    assert_eq!(r2(QSUB, 0x8000_0000, 1), (0x8000_0000, true));
    const QDADD: &[u16] = &[
        // asm: qdadd
        0xFA81, 0xF290, // 00: qdadd r2, r0, r1
    ];
    // R0 + sat(2 × R1): doubling 0x4000_0000 saturates, and so does the sum.
    assert_eq!(r2(QDADD, 1, 0x4000_0000), (0x7FFF_FFFF, true));
    assert_eq!(r2(QDADD, 1, 3), (7, false));
}

#[test]
fn saturate_instructions() {
    const SSAT: &[u16] = &[
        // asm: ssat
        0xF300, 0x0207, // 00: ssat r2, #0x8, r0
    ];
    assert_eq!(r2(SSAT, 300, 0), (127, true));
    assert_eq!(r2(SSAT, (-300i32) as u32, 0), ((-128i32) as u32, true));
    assert_eq!(r2(SSAT, (-5i32) as u32, 0), ((-5i32) as u32, false));
    const SSAT_ASR: &[u16] = &[
        // asm: ssat_asr
        0xF320, 0x120F, // 00: ssat r2, #0x10, r0, asr #4
    ];
    assert_eq!(r2(SSAT_ASR, 0x0010_0000, 0), (0x7FFF, true));
    assert_eq!(r2(SSAT_ASR, 0x0000_1230, 0), (0x123, false));
    const USAT: &[u16] = &[
        // asm: usat
        0xF380, 0x0208, // 00: usat r2, #0x8, r0
    ];
    assert_eq!(r2(USAT, (-1i32) as u32, 0), (0, true));
    assert_eq!(r2(USAT, 256, 0), (255, true));
    assert_eq!(r2(USAT, 200, 0), (200, false));
    const SSAT16: &[u16] = &[
        // asm: ssat16
        0xF320, 0x0203, // 00: ssat16 r2, #0x4, r0
    ];
    // Four bits signed: -8..7 per halfword.
    assert_eq!(r2(SSAT16, 0xFFF0_0005, 0), (0xFFF8_0005, true));
    const USAT16: &[u16] = &[
        // asm: usat16
        0xF3A0, 0x0204, // 00: usat16 r2, #0x4, r0
    ];
    assert_eq!(r2(USAT16, 0x0020_FFFF, 0), (0x000F_0000, true));
}

#[test]
fn parallel_saturating_lanes() {
    const UQADD16: &[u16] = &[
        // asm: uqadd16
        0xFA90, 0xF251, // 00: uqadd16 r2, r0, r1
    ];
    assert_eq!(r2(UQADD16, 0xFFF0_1000, 0x0020_0234), (0xFFFF_1234, false));
    const UQSUB8: &[u16] = &[
        // asm: uqsub8
        0xFAC0, 0xF251, // 00: uqsub8 r2, r0, r1
    ];
    assert_eq!(r2(UQSUB8, 0x1020_3040, 0x2010_4010), (0x0010_0030, false));
}

#[test]
fn ge_flags_drive_sel() {
    const SADD16: &[u16] = &[
        // asm: sadd16_sel
        0xFA90, 0xF201, // 00: sadd16 r2, r0, r1
        0xFAA0, 0xF381, // 04: sel r3, r0, r1
    ];
    // Low lane 5 + -7 < 0, high lane 1 + 2 ≥ 0: GE = 0b1100, SEL takes the high half of R0.
    let rig = run(SADD16, &[(0, 0x0001_0005), (1, 0x0002_FFF9)]);
    assert_eq!(rig.r(2), 0x0003_FFFE);
    assert_eq!(rig.ge(), 0b1100);
    assert_eq!(rig.r(3), 0x0001_FFF9);
    const USUB8: &[u16] = &[
        // asm: usub8_sel
        0xFAC0, 0xF241, // 00: usub8 r2, r0, r1
        0xFAA0, 0xF381, // 04: sel r3, r0, r1
    ];
    // Bytes 0 and 3 do not borrow.
    let rig = run(USUB8, &[(0, 0x9010_2030), (1, 0x8020_3010)]);
    assert_eq!(rig.ge(), 0b1001);
    assert_eq!(rig.r(3), 0x9020_3030);
}

#[test]
fn halving_and_exchanging_lanes() {
    const UHADD8: &[u16] = &[
        // asm: uhadd8
        0xFA80, 0xF261, // 00: uhadd8 r2, r0, r1
    ];
    assert_eq!(r2(UHADD8, 0xFF01_0203, 0xFF01_0405).0, 0xFF01_0304);
    const SHSUB16: &[u16] = &[
        // asm: shsub16
        0xFAD0, 0xF221, // 00: shsub16 r2, r0, r1
    ];
    assert_eq!(r2(SHSUB16, 0x8000_0003, 0x7FFF_0008).0, 0x8000_FFFD);
    const SASX: &[u16] = &[
        // asm: sasx
        0xFAA0, 0xF201, // 00: sasx r2, r0, r1
    ];
    // high = R0.hi + R1.lo, low = R0.lo - R1.hi.
    let rig = run(SASX, &[(0, 0x0010_0020), (1, 0x0030_0004)]);
    assert_eq!(rig.r(2), 0x0014_FFF0);
    assert_eq!(rig.ge(), 0b1100);
    const UASX: &[u16] = &[
        // asm: uasx
        0xFAA0, 0xF241, // 00: uasx r2, r0, r1
    ];
    let rig = run(UASX, &[(0, 0xFFFF_0040), (1, 0x0010_0001)]);
    assert_eq!(rig.r(2), 0x0000_0030);
    assert_eq!(rig.ge(), 0b1111);
    const QSAX: &[u16] = &[
        // asm: qsax
        0xFAE0, 0xF211, // 00: qsax r2, r0, r1
    ];
    // high = sat(R0.hi - R1.lo), low = sat(R0.lo + R1.hi).
    assert_eq!(r2(QSAX, 0x8000_7FFF, 0x0001_0001).0, 0x8000_7FFF);
}

#[test]
fn halfword_multiplies_and_their_q() {
    const SMLABB: &[u16] = &[
        // asm: smlabb
        0xFB10, 0x3201, // 00: smlabb r2, r0, r1, r3
    ];
    let rig = run(
        SMLABB,
        &[(0, 0x7FFF_8000), (1, 0x1234_8000), (3, 0x7FFF_FFFF)],
    );
    // (-32768)² + 0x7FFF_FFFF overflows 32 bits: Q.
    assert_eq!(rig.r(2), 0x7FFF_FFFFu32.wrapping_add(0x4000_0000));
    assert!(rig.q());
    const SMULTT: &[u16] = &[
        // asm: smultt
        0xFB10, 0xF231, // 00: smultt r2, r0, r1
    ];
    assert_eq!(
        r2(SMULTT, 0xFFFE_0000, 0x0003_0000),
        ((-6i32) as u32, false)
    );
    const SMLAWB: &[u16] = &[
        // asm: smlawb
        0xFB30, 0x3201, // 00: smlawb r2, r0, r1, r3
    ];
    let rig = run(SMLAWB, &[(0, 0x0001_0000), (1, 0x0000_0004), (3, 10)]);
    assert_eq!(rig.r(2), 14);
    const SMULWT: &[u16] = &[
        // asm: smulwt
        0xFB30, 0xF211, // 00: smulwt r2, r0, r1
    ];
    assert_eq!(r2(SMULWT, 0xFFFF_0000, 0x0002_0000).0, 0xFFFF_FFFE);
}

#[test]
fn dual_multiplies() {
    const SMLAD: &[u16] = &[
        // asm: smlad
        0xFB20, 0x3201, // 00: smlad r2, r0, r1, r3
    ];
    let rig = run(SMLAD, &[(0, 0x0002_0003), (1, 0x0004_0005), (3, 100)]);
    assert_eq!(rig.r(2), 100 + 8 + 15);
    const SMLADX: &[u16] = &[
        // asm: smladx
        0xFB20, 0x3211, // 00: smladx r2, r0, r1, r3
    ];
    let rig = run(SMLADX, &[(0, 0x0002_0003), (1, 0x0004_0005), (3, 0)]);
    assert_eq!(rig.r(2), 2 * 5 + 3 * 4);
    const SMUSD: &[u16] = &[
        // asm: smusd
        0xFB40, 0xF201, // 00: smusd r2, r0, r1
    ];
    assert_eq!(r2(SMUSD, 0x0002_0003, 0x0004_0005).0, 15 - 8);
    const SMLSLD: &[u16] = &[
        // asm: smlsld
        0xFBD0, 0x23C1, // 00: smlsld r2, r3, r0, r1
    ];
    let rig = run(
        SMLSLD,
        &[(0, 0x0002_0003), (1, 0x0004_0005), (2, 0), (3, 0)],
    );
    assert_eq!((rig.r(3), rig.r(2)), (0, 7));
    const SMLALBT: &[u16] = &[
        // asm: smlalbt
        0xFBC0, 0x2391, // 00: smlalbt r2, r3, r0, r1
    ];
    let rig = run(
        SMLALBT,
        &[(0, 0x0000_FFFF), (1, 0x0003_0000), (2, 0), (3, 0)],
    );
    assert_eq!((rig.r(3), rig.r(2)), (0xFFFF_FFFF, (-3i32) as u32));
}

#[test]
fn most_significant_word_multiplies_round() {
    const SMMUL: &[u16] = &[
        // asm: smmul
        0xFB50, 0xF201, // 00: smmul r2, r0, r1
        0xFB50, 0xF311, // 04: smmulr r3, r0, r1
    ];
    // 0x4000_0001 × 0x4000_0001 = 0x1000_0000_8000_0001: the R form rounds up.
    let rig = run(SMMUL, &[(0, 0x4000_0001), (1, 0x4000_0001)]);
    assert_eq!((rig.r(2), rig.r(3)), (0x1000_0000, 0x1000_0001));
    const SMMLA: &[u16] = &[
        // asm: smmla
        0xFB50, 0x4201, // 00: smmla r2, r0, r1, r4
        0xFB60, 0x4301, // 04: smmls r3, r0, r1, r4
    ];
    let rig = run(SMMLA, &[(0, 0x0001_0000), (1, 0x0001_0000), (4, 5)]);
    assert_eq!((rig.r(2), rig.r(3)), (6, 4));
}

#[test]
fn packing_and_extension() {
    const PKH: &[u16] = &[
        // asm: pkh
        0xEAC0, 0x2201, // 00: pkhbt r2, r0, r1, lsl #8
        0xEAC0, 0x2321, // 04: pkhtb r3, r0, r1, asr #8
    ];
    let rig = run(PKH, &[(0, 0x1111_2222), (1, 0x8033_4455)]);
    assert_eq!(rig.r(2), 0x3344_2222);
    assert_eq!(rig.r(3), 0x1111_3344);
    const EXT: &[u16] = &[
        // asm: extend
        0xFA54, 0xF290, // 00: uxtab r2, r4, r0, ror #8
        0xFA04, 0xF380, // 04: sxtah r3, r4, r0
        0xFA3F, 0xF580, // 08: uxtb16 r5, r0
        0xFA24, 0xF6A0, // 0c: sxtab16 r6, r4, r0, ror #16
    ];
    let rig = run(EXT, &[(0, 0x80FF_8001), (4, 0x0001_0001)]);
    assert_eq!(rig.r(2), 0x0001_0001 + 0x80);
    assert_eq!(rig.r(3), 0x0001_0001u32.wrapping_add(0xFFFF_8001));
    assert_eq!(rig.r(5), 0x00FF_0001);
    // ROR #16 gives 0x8001_80FF: bytes 0 (0xFF = -1) and 2 (0x01) extend into the halves.
    assert_eq!(rig.r(6), 0x0002_0000);
}

#[test]
fn sum_of_absolute_differences() {
    const USAD8: &[u16] = &[
        // asm: usad8
        0xFB70, 0xF201, // 00: usad8 r2, r0, r1
        0xFB70, 0x4301, // 04: usada8 r3, r0, r1, r4
    ];
    let rig = run(USAD8, &[(0, 0x0110_FF00), (1, 0x0301_00FF), (4, 1000)]);
    assert_eq!(rig.r(2), 2 + 15 + 255 + 255);
    assert_eq!(rig.r(3), 1000 + 527);
}

#[test]
fn msr_writes_the_flags_q_and_ge() {
    const MSR: &[u16] = &[
        // asm: msr_apsr
        0xF380, 0x8C00, // 00: msr apsr_nzcvqg, r0
        0xF3EF, 0x8100, // 04: mrs r1, apsr
    ];
    let rig = run(MSR, &[(0, 0xF80F_0000)]);
    assert_eq!(rig.r(1), 0xF80F_0000);
    assert!(rig.q());
    assert_eq!(rig.ge(), 0xF);
}
