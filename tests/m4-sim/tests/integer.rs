//! Integer instructions, hand-assembled (the comments give the assembly; the encodings
//! come from the ARMv7-M ARM's tables), with results and flags worked from the manual's
//! pseudocode.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

mod common;
use common::*;
use m4_sim::Stop;

/// Runs `code` with registers set by `regs` and returns the rig at the final BKPT.
fn run(code: &[u16], regs: &[(u8, u32)]) -> Rig {
    let mut rig = Rig::new(code);
    for &(r, v) in regs {
        rig.set(r, v);
    }
    rig.run_to_end(code.len());
    rig
}

#[test]
fn adds_sets_overflow_and_negative() {
    const CODE: &[u16] = &[
        // asm: adds
        0x1888, // 00: adds r0, r1, r2
    ];
    let rig = run(CODE, &[(1, 0x7FFF_FFFF), (2, 1)]);
    assert_eq!(rig.r(0), 0x8000_0000);
    assert_eq!(rig.nzcv(), (true, false, false, true));
    let rig = run(CODE, &[(1, 0xFFFF_FFFF), (2, 1)]);
    assert_eq!(rig.r(0), 0);
    assert_eq!(rig.nzcv(), (false, true, true, false));
}

#[test]
fn subs_borrow_clears_carry() {
    const CODE: &[u16] = &[
        // asm: subs
        0x1B63, // 00: subs r3, r4, r5
    ];
    let rig = run(CODE, &[(4, 5), (5, 7)]);
    assert_eq!(rig.r(3), 0xFFFF_FFFE);
    assert_eq!(rig.nzcv(), (true, false, false, false));
    let rig = run(CODE, &[(4, 0x8000_0000), (5, 1)]);
    assert_eq!(rig.r(3), 0x7FFF_FFFF);
    assert_eq!(rig.nzcv(), (false, false, true, true));
}

#[test]
fn carry_chains_make_64_bit_arithmetic() {
    const ADD: &[u16] = &[
        // asm: add64
        0x1880, // 00: adds r0, r0, r2
        0x4159, // 02: adcs r1, r3
    ];
    let rig = run(ADD, &[(0, 0xFFFF_FFFF), (1, 1), (2, 1), (3, 0)]);
    assert_eq!((rig.r(1), rig.r(0)), (2, 0));
    const SUB: &[u16] = &[
        // asm: sub64
        0x1A80, // 00: subs r0, r0, r2
        0x4199, // 02: sbcs r1, r3
    ];
    let rig = run(SUB, &[(0, 0), (1, 2), (2, 1), (3, 0)]);
    assert_eq!((rig.r(1), rig.r(0)), (1, 0xFFFF_FFFF));
}

#[test]
fn register_shifts_of_32_and_more() {
    const LSL: &[u16] = &[
        // asm: lsls_reg
        0x4088, // 00: lsls r0, r1
    ];
    const LSR: &[u16] = &[
        // asm: lsrs_reg
        0x40C8, // 00: lsrs r0, r1
    ];
    const ASR: &[u16] = &[
        // asm: asrs_reg
        0x4108, // 00: asrs r0, r1
    ];
    const ROR: &[u16] = &[
        // asm: rors_reg
        0x41C8, // 00: rors r0, r1
    ];
    // (code, value, amount, result, carry)
    let cases: &[(&[u16], u32, u32, u32, bool)] = &[
        (LSL, 1, 32, 0, true),
        (LSL, 1, 33, 0, false),
        (LSL, 0x8000_0001, 1, 2, true),
        (LSL, 3, 0x100, 3, true), // only Rm<7:0> counts: a zero shift keeps C
        (LSR, 0x8000_0000, 32, 0, true),
        (LSR, 0x8000_0000, 255, 0, false),
        (ASR, 0x8000_0000, 40, 0xFFFF_FFFF, true),
        (ASR, 0x7000_0000, 32, 0, false),
        (ROR, 0x0000_0001, 1, 0x8000_0000, true),
        (ROR, 0x8000_0000, 32, 0x8000_0000, true),
        (ROR, 0x0000_0002, 33, 0x0000_0001, false),
    ];
    for &(code, value, amount, result, carry) in cases {
        let mut rig = Rig::new(code);
        rig.set(0, value);
        rig.set(1, amount);
        rig.set_nzcv(false, false, true, false);
        rig.run_to_end(code.len());
        assert_eq!(rig.r(0), result, "{value:#x} by {amount}");
        assert_eq!(rig.nzcv().2, carry, "carry of {value:#x} by {amount}");
    }
}

#[test]
fn rrx_rotates_through_the_carry() {
    const CODE: &[u16] = &[
        // asm: rrxs
        0xEA5F, 0x0031, // 00: rrxs r0, r1
    ];
    let mut rig = Rig::new(CODE);
    rig.set(1, 3);
    rig.set_nzcv(false, false, true, false);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.r(0), 0x8000_0001);
    assert_eq!(rig.nzcv(), (true, false, true, false));
}

#[test]
fn modified_immediates_set_the_carry_only_when_rotated() {
    const MOVS: &[u16] = &[
        // asm: movs_rot
        0xF05F, 0x4000, // 00: movs.w r0, #0x80000000
    ];
    let mut rig = Rig::new(MOVS);
    rig.set_nzcv(false, false, false, false);
    rig.run_to_end(MOVS.len());
    assert_eq!(rig.r(0), 0x8000_0000);
    assert_eq!(rig.nzcv(), (true, false, true, false));
    const ANDS: &[u16] = &[
        // asm: ands_plain
        0xF011, 0x00FF, // 00: ands r0, r1, #0xff
    ];
    let mut rig = Rig::new(ANDS);
    rig.set(1, 0x1234_5600);
    rig.set_nzcv(false, false, true, true);
    rig.run_to_end(ANDS.len());
    assert_eq!(rig.r(0), 0);
    assert_eq!(rig.nzcv(), (false, true, true, true));
    const TST: &[u16] = &[
        // asm: tst_shifted
        0xEA11, 0x7FC2, // 00: tst.w r1, r2, lsl #31
    ];
    // 3 << 31 carries out bit 1; the result 0x8000_0000 is negative.
    let rig = run(TST, &[(1, 0xFFFF_FFFF), (2, 3)]);
    assert_eq!(rig.nzcv(), (true, false, true, false));
}

#[test]
fn an_immediate_shift_of_32_carries_out_bit_31() {
    const CODE: &[u16] = &[
        // asm: shift_imm_carry
        0x0808, // 00: lsrs r0, r1, #0x20
    ];
    let rig = run(CODE, &[(1, 0x8000_0000)]);
    assert_eq!(rig.r(0), 0);
    assert_eq!(rig.nzcv(), (false, true, true, false));
}

#[test]
fn it_blocks_execute_by_condition_and_count_every_instruction() {
    const CODE: &[u16] = &[
        // asm: it_block
        0x2805, // 00: cmp r0, #0x5
        0xBF0C, // 02: ite eq
        0x2101, // 04: moveq r1, #0x1
        0x2102, // 06: movne r1, #0x2
        0xBF1C, // 08: itt ne
        0x1C52, // 0a: addne r2, r2, #0x1
        0x1E5B, // 0c: subne r3, r3, #0x1
    ];
    let rig = run(CODE, &[(0, 5), (2, 10), (3, 10)]);
    assert_eq!((rig.r(1), rig.r(2), rig.r(3)), (1, 10, 10));
    // cmp, ite, 2 moves, itt, 2 adds, bkpt: condition-failed instructions count too.
    assert_eq!(rig.cpu.stats().instructions, 8);
    let rig = run(CODE, &[(0, 4), (2, 10), (3, 10)]);
    assert_eq!((rig.r(1), rig.r(2), rig.r(3)), (2, 11, 9));
    const FOUR: &[u16] = &[
        // asm: it4
        0x2800, // 00: cmp r0, #0x0
        0xBFCB, // 02: itete gt
        0x2101, // 04: movgt r1, #0x1
        0x2102, // 06: movle r1, #0x2
        0x2203, // 08: movgt r2, #0x3
        0x2204, // 0a: movle r2, #0x4
    ];
    let rig = run(FOUR, &[(0, 1)]);
    assert_eq!((rig.r(1), rig.r(2)), (1, 3));
    let rig = run(FOUR, &[(0, 0)]);
    assert_eq!((rig.r(1), rig.r(2)), (2, 4));
}

#[test]
fn sixteen_bit_arithmetic_in_an_it_block_leaves_the_flags() {
    const CODE: &[u16] = &[
        // asm: it_flags
        0x2400, // 00: movs r4, #0x0
        0x4280, // 02: cmp r0, r0
        0xBF08, // 04: it eq
        0x3401, // 06: addeq r4, #0x1
    ];
    let rig = run(CODE, &[(0, 7)]);
    // movs r4,#0 set Z; cmp set Z; the `adds` encoding inside IT does not set flags.
    assert_eq!(rig.r(4), 1);
    assert!(rig.nzcv().1);
}

#[test]
fn compare_and_branch_on_zero() {
    const CODE: &[u16] = &[
        // asm: cbz
        0xB100, // 00: cbz r0, 0x4 <.text+0x4> @ imm = #0x0
        0x2101, // 02: movs r1, #0x1
        0xB900, // 04: cbnz r0, 0x8 <.text+0x8> @ imm = #0x0
        0x2201, // 06: movs r2, #0x1
        0xBF00, // 08: nop
    ];
    let rig = run(CODE, &[(0, 0), (1, 0), (2, 0)]);
    assert_eq!((rig.r(1), rig.r(2)), (0, 1));
    let rig = run(CODE, &[(0, 9), (1, 0), (2, 0)]);
    assert_eq!((rig.r(1), rig.r(2)), (1, 0));
}

#[test]
fn table_branches() {
    const TBB: &[u16] = &[
        // asm: tbb
        0xE8DF, 0xF000, // 00: tbb [pc, r0]
        0x0402, 0x0006, // 04: .word 0x00060402
        0x210A, // 08: movs r1, #0xa
        0xE003, // 0a: b 0x14 <.text+0x14> @ imm = #0x6
        0x210B, // 0c: movs r1, #0xb
        0xE001, // 0e: b 0x14 <.text+0x14> @ imm = #0x2
        0x210C, // 10: movs r1, #0xc
        0xE7FF, // 12: b 0x14 <.text+0x14> @ imm = #-0x2
        0xBF00, // 14: nop
    ];
    for (i, want) in [10, 11, 12].into_iter().enumerate() {
        let rig = run(TBB, &[(0, i as u32)]);
        assert_eq!(rig.r(1), want);
    }
    const TBH: &[u16] = &[
        // asm: tbh
        0xE8DF, 0xF010, // 00: tbh [pc, r0, lsl #1]
        0x0002, 0x0004, // 04: .word 0x00040002
        0x2114, // 08: movs r1, #0x14
        0xE000, // 0a: b 0xe <.text+0xe> @ imm = #0x0
        0x2115, // 0c: movs r1, #0x15
        0xBF00, // 0e: nop
    ];
    for (i, want) in [20, 21].into_iter().enumerate() {
        let rig = run(TBH, &[(0, i as u32)]);
        assert_eq!(rig.r(1), want);
    }
}

#[test]
fn push_pop_and_multiple_transfers() {
    const PUSHPOP: &[u16] = &[
        // asm: pushpop
        0xB530, // 00: push {r4, r5, lr}
        0x2400, // 02: movs r4, #0x0
        0x2500, // 04: movs r5, #0x0
        0xBC70, // 06: pop {r4, r5, r6}
    ];
    let rig = run(PUSHPOP, &[(4, 44), (5, 55), (14, 0x1EE)]);
    assert_eq!((rig.r(4), rig.r(5), rig.r(6)), (44, 55, 0x1EE));
    assert_eq!(rig.r(13), STACK);
    assert_eq!(rig.word(STACK - 4), 0x1EE);
    assert_eq!(rig.cpu.stats().lowest_sp, STACK - 12);
    const LDM: &[u16] = &[
        // asm: ldm_stm
        0xC00E, // 00: stm r0!, {r1, r2, r3}
        0xE930, 0x0070, // 02: ldmdb r0!, {r4, r5, r6}
    ];
    let rig = run(LDM, &[(0, DATA), (1, 1), (2, 2), (3, 3)]);
    assert_eq!(rig.r(0), DATA);
    assert_eq!((rig.r(4), rig.r(5), rig.r(6)), (1, 2, 3));
    assert_eq!(rig.word(DATA + 8), 3);
}

#[test]
fn dual_transfers_with_writeback() {
    const CODE: &[u16] = &[
        // asm: ldrd_strd
        0xE9E0, 0x2302, // 00: strd r2, r3, [r0, #8]!
        0xE870, 0x4502, // 04: ldrd r4, r5, [r0], #-8
    ];
    let rig = run(CODE, &[(0, DATA), (2, 0xAAAA), (3, 0xBBBB)]);
    assert_eq!(rig.word(DATA + 8), 0xAAAA);
    assert_eq!(rig.word(DATA + 12), 0xBBBB);
    assert_eq!((rig.r(4), rig.r(5)), (0xAAAA, 0xBBBB));
    assert_eq!(rig.r(0), DATA);
}

#[test]
fn load_addressing_modes_and_extension() {
    const CODE: &[u16] = &[
        // asm: ldr_modes
        0x6841, // 00: ldr r1, [r0, #0x4]
        0xF850, 0x2B04, // 02: ldr r2, [r0], #4
        0xF850, 0x3F04, // 06: ldr r3, [r0, #4]!
        0xF810, 0x4C01, // 0a: ldrb r4, [r0, #-1]
        0xF910, 0x5C01, // 0e: ldrsb r5, [r0, #-1]
        0x8846, // 12: ldrh r6, [r0, #0x2]
        0xF9B0, 0x7002, // 14: ldrsh.w r7, [r0, #0x2]
    ];
    let mut rig = Rig::new(CODE);
    rig.poke(DATA, 0x1111_1111);
    rig.poke(DATA + 4, 0x8081_2222);
    rig.poke(DATA + 8, 0xF00D_8003);
    rig.set(0, DATA);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.r(1), 0x8081_2222);
    assert_eq!(rig.r(2), 0x1111_1111);
    assert_eq!(rig.r(3), 0xF00D_8003);
    assert_eq!(rig.r(0), DATA + 8);
    assert_eq!((rig.r(4), rig.r(5)), (0x80, 0xFFFF_FF80));
    assert_eq!((rig.r(6), rig.r(7)), (0xF00D, 0xFFFF_F00D));
    const REG: &[u16] = &[
        // asm: ldr_reg
        0xF850, 0x1022, // 00: ldr.w r1, [r0, r2, lsl #2]
        0xF800, 0x3002, // 04: strb.w r3, [r0, r2]
    ];
    let mut rig = Rig::new(REG);
    rig.poke(DATA + 12, 0x1234);
    rig.set(0, DATA);
    rig.set(2, 3);
    rig.set(3, 0x1FF);
    rig.run_to_end(REG.len());
    assert_eq!(rig.r(1), 0x1234);
    assert_eq!(rig.word(DATA) >> 24, 0xFF);
    const LIT: &[u16] = &[
        // asm: ldr_lit
        0x4800, // 00: ldr r0, [pc, #0x0] @ 0x4 <.text+0x4>
        0xE001, // 02: b 0x8 <.text+0x8> @ imm = #0x2
        0xF00D, 0xCAFE, // 04: .word 0xcafef00d
        0xBF00, // 08: nop
    ];
    let rig = run(LIT, &[]);
    assert_eq!(rig.r(0), 0xCAFE_F00D);
}

#[test]
fn unaligned_word_loads_split_unless_trapped() {
    const CODE: &[u16] = &[
        // asm: ldr_modes
        0x6841, // 00: ldr r1, [r0, #0x4]
        0xF850, 0x2B04, // 02: ldr r2, [r0], #4
        0xF850, 0x3F04, // 06: ldr r3, [r0, #4]!
        0xF810, 0x4C01, // 0a: ldrb r4, [r0, #-1]
        0xF910, 0x5C01, // 0e: ldrsb r5, [r0, #-1]
        0x8846, // 12: ldrh r6, [r0, #0x2]
        0xF9B0, 0x7002, // 14: ldrsh.w r7, [r0, #0x2]
    ];
    let mut rig = Rig::new(&CODE[..1]);
    rig.poke(DATA + 4, 0x4433_2211);
    rig.poke(DATA + 8, 0x8877_6655);
    rig.set(0, DATA + 2);
    rig.run_to_end(1);
    assert_eq!(rig.r(1), 0x6655_4433);
}

#[test]
fn loads_into_the_pc_interwork() {
    const CODE: &[u16] = &[
        // asm: ldr_pc
        0xF8D0, 0xF000, // 00: ldr.w pc, [r0]
    ];
    let mut rig = Rig::new(CODE);
    rig.place(0x300, &[0xBE05]);
    rig.poke(DATA, 0x301);
    rig.set(0, DATA);
    assert_eq!(rig.run(), Stop::Breakpoint { pc: 0x300, imm: 5 });
}

#[test]
fn branch_with_link() {
    const BLX: &[u16] = &[
        // asm: blx
        0x4780, // 00: blx r0
    ];
    let mut rig = Rig::new(BLX);
    rig.place(0x300, &[0xBE05]);
    rig.set(0, 0x301);
    assert_eq!(rig.run(), Stop::Breakpoint { pc: 0x300, imm: 5 });
    assert_eq!(rig.r(14), (CODE + 2) | 1);
    const BL: &[u16] = &[
        // asm: bl
        0xF000, 0xF802, // 00: bl 0x8 <.text+0x8> @ imm = #0x4
        0x2101, // 04: movs r1, #0x1
        0xE001, // 06: b 0xc <.text+0xc> @ imm = #0x2
        0x2202, // 08: movs r2, #0x2
        0x4770, // 0a: bx lr
        0xBF00, // 0c: nop
    ];
    let rig = run(BL, &[]);
    assert_eq!((rig.r(1), rig.r(2)), (1, 2));
}

#[test]
fn exclusives_succeed_once_and_fail_after_clrex() {
    const CODE: &[u16] = &[
        // asm: exclusive
        0xE850, 0x1F00, // 00: ldrex r1, [r0]
        0x3101, // 04: adds r1, #0x1
        0xE840, 0x1200, // 06: strex r2, r1, [r0]
        0xE850, 0x3F00, // 0a: ldrex r3, [r0]
        0xF3BF, 0x8F2F, // 0e: clrex
        0xE840, 0x1400, // 12: strex r4, r1, [r0]
    ];
    let mut rig = Rig::new(CODE);
    rig.poke(DATA, 41);
    rig.set(0, DATA);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.r(2), 0, "the first STREX stores");
    assert_eq!(rig.word(DATA), 42);
    assert_eq!(rig.r(3), 42);
    assert_eq!(rig.r(4), 1, "CLREX makes the second fail");
}

#[test]
fn bit_fields_reversals_and_counts() {
    const BF: &[u16] = &[
        // asm: bitfield
        0xF361, 0x200B, // 00: bfi r0, r1, #8, #4
        0xF36F, 0x020F, // 04: bfc r2, #0, #16
        0xF3C4, 0x1307, // 08: ubfx r3, r4, #0x4, #0x8
        0xF344, 0x1507, // 0c: sbfx r5, r4, #0x4, #0x8
    ];
    let rig = run(
        BF,
        &[
            (0, 0xFFFF_FFFF),
            (1, 0x5),
            (2, 0x1234_5678),
            (4, 0x0000_0F70),
        ],
    );
    assert_eq!(rig.r(0), 0xFFFF_F5FF);
    assert_eq!(rig.r(2), 0x1234_0000);
    assert_eq!(rig.r(3), 0xF7);
    assert_eq!(rig.r(5), 0xFFFF_FFF7);
    const REV: &[u16] = &[
        // asm: rev
        0xBA01, // 00: rev r1, r0
        0xBA42, // 02: rev16 r2, r0
        0xBAC3, // 04: revsh r3, r0
        0xFA90, 0xF4A0, // 06: rbit r4, r0
        0xFAB0, 0xF580, // 0a: clz r5, r0
    ];
    let rig = run(REV, &[(0, 0x0012_80F0)]);
    assert_eq!(rig.r(1), 0xF080_1200);
    assert_eq!(rig.r(2), 0x1200_F080);
    assert_eq!(rig.r(3), 0xFFFF_F080);
    assert_eq!(rig.r(4), 0x0F01_4800);
    assert_eq!(rig.r(5), 11);
}

#[test]
fn multiplies() {
    const MUL: &[u16] = &[
        // asm: mul
        0x4341, // 00: muls r1, r0, r1
        0xFB00, 0x3200, // 02: mla r2, r0, r0, r3
        0xFB00, 0x3410, // 06: mls r4, r0, r0, r3
    ];
    let rig = run(MUL, &[(0, 0x1_0001), (1, 0x1_0001), (3, 5)]);
    assert_eq!(rig.r(1), 0x0002_0001);
    assert_eq!(rig.r(2), 0x0002_0006);
    assert_eq!(rig.r(4), 5u32.wrapping_sub(0x0002_0001));
    const LONG: &[u16] = &[
        // asm: mullong
        0xFBA2, 0x0103, // 00: umull r0, r1, r2, r3
        0xFB82, 0x4503, // 04: smull r4, r5, r2, r3
    ];
    let rig = run(LONG, &[(2, 0xFFFF_FFFF), (3, 2)]);
    assert_eq!((rig.r(1), rig.r(0)), (1, 0xFFFF_FFFE));
    assert_eq!((rig.r(5), rig.r(4)), (0xFFFF_FFFF, 0xFFFF_FFFE));
    const ACC: &[u16] = &[
        // asm: mullong_acc
        0xFBE2, 0x0103, // 00: umlal r0, r1, r2, r3
        0xFBC2, 0x4503, // 04: smlal r4, r5, r2, r3
        0xFBE2, 0x6763, // 08: umaal r6, r7, r2, r3
    ];
    let rig = run(
        ACC,
        &[
            (0, 0xFFFF_FFFF),
            (1, 0),
            (2, 0xFFFF_FFFF),
            (3, 0xFFFF_FFFF),
            (4, 1),
            (5, 0),
            (6, 0xFFFF_FFFF),
            (7, 0xFFFF_FFFF),
        ],
    );
    // 0xFFFFFFFF² + 0xFFFFFFFF = 0xFFFFFFFF_00000000
    assert_eq!((rig.r(1), rig.r(0)), (0xFFFF_FFFF, 0));
    // (-1)(-1) + 1 = 2
    assert_eq!((rig.r(5), rig.r(4)), (0, 2));
    // UMAAL: the largest case still fits 64 bits.
    assert_eq!((rig.r(7), rig.r(6)), (0xFFFF_FFFF, 0xFFFF_FFFF));
}

#[test]
fn divides_round_toward_zero_and_by_zero_gives_zero() {
    const DIV: &[u16] = &[
        // asm: div
        0xFB90, 0xF2F1, // 00: sdiv r2, r0, r1
        0xFBB0, 0xF3F1, // 04: udiv r3, r0, r1
    ];
    let rig = run(DIV, &[(0, (-7i32) as u32), (1, 2)]);
    assert_eq!(rig.r(2), (-3i32) as u32);
    assert_eq!(rig.r(3), 0x7FFF_FFFC);
    let rig = run(DIV, &[(0, 0x8000_0000), (1, 0xFFFF_FFFF)]);
    assert_eq!(rig.r(2), 0x8000_0000);
    let rig = run(DIV, &[(0, 5), (1, 0)]);
    assert_eq!((rig.r(2), rig.r(3)), (0, 0));
}

#[test]
fn divide_by_zero_traps_when_enabled() {
    const CODE: &[u16] = &[
        // asm: div_zero
        0xFBB0, 0xF2F1, // 00: udiv r2, r0, r1
    ];
    let mut rig = Rig::new(CODE);
    rig.scs_write(0xE000_ED14, 1 << 4 | 1 << 9); // CCR.DIV_0_TRP
    rig.scs_write(0xE000_ED24, 1 << 18); // SHCSR.USGFAULTENA
    rig.set(0, 5);
    rig.set(1, 0);
    rig.run_to_handler(6);
    assert_eq!(rig.scs_read(0xE000_ED28), 1 << 25); // UFSR.DIVBYZERO
    // The stacked return address is the faulting instruction.
    assert_eq!(rig.word(rig.r(13) + 24), CODE_ADDR);
}

const CODE_ADDR: u32 = CODE;

#[test]
fn pc_relative_values_and_wide_immediates() {
    const ADR: &[u16] = &[
        // asm: adr_addw
        0xA002, // 00: adr r0, #8 <.text+0x6>
        0xF600, 0x21BC, // 02: addw r1, r0, #0xabc
        0xF2A0, 0x0201, // 06: subw r2, r0, #0x1
        0xBF00, // 0a: nop
        0xBF00, // 0c: nop
    ];
    let rig = run(ADR, &[]);
    let base = rig.r(0);
    assert_eq!(base % 4, 0);
    assert!(base > CODE && base < CODE + 2 * ADR.len() as u32 + 4);
    assert_eq!(rig.r(1), base + 0xABC);
    assert_eq!(rig.r(2), base - 1);
    const MOV: &[u16] = &[
        // asm: movw_movt
        0xF245, 0x6078, // 00: movw r0, #0x5678
        0xF2C1, 0x2034, // 04: movt r0, #0x1234
    ];
    assert_eq!(run(MOV, &[]).r(0), 0x1234_5678);
}

#[test]
fn stack_pointer_arithmetic_and_high_registers() {
    const SP: &[u16] = &[
        // asm: sp_ops
        0xB084, // 00: sub sp, #0x10
        0xA802, // 02: add r0, sp, #0x8
        0xB004, // 04: add sp, #0x10
        0x4669, // 06: mov r1, sp
    ];
    let rig = run(SP, &[]);
    assert_eq!(rig.r(0), STACK - 8);
    assert_eq!(rig.r(1), STACK);
    const CMP: &[u16] = &[
        // asm: cmp_high
        0x4680, // 00: mov r8, r0
        0x4588, // 02: cmp r8, r1
    ];
    let rig = run(CMP, &[(0, 3), (1, 3)]);
    assert_eq!(rig.r(8), 3);
    assert!(rig.nzcv().1);
    const NEG: &[u16] = &[
        // asm: neg
        0x4241, // 00: rsbs r1, r0, #0
    ];
    let rig = run(NEG, &[(0, 1)]);
    assert_eq!(rig.r(1), 0xFFFF_FFFF);
    assert_eq!(rig.nzcv(), (true, false, false, false));
}

#[test]
fn udf_is_a_usage_fault_escalated_to_hard_fault_when_disabled() {
    const CODE: &[u16] = &[
        // asm: udf
        0xDE07, // 00: udf #0x7
    ];
    let mut rig = Rig::new(CODE);
    rig.run_to_handler(3);
    assert_eq!(rig.scs_read(0xE000_ED28), 1 << 16); // UNDEFINSTR
    assert_eq!(rig.scs_read(0xE000_ED2C), 1 << 30); // HFSR.FORCED
    let mut rig = Rig::new(CODE);
    rig.scs_write(0xE000_ED24, 1 << 18);
    rig.run_to_handler(6);
}
