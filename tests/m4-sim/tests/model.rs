//! The cycle model's figures (Cortex-M4 TRM table 3-1, FPU TRM), measured between two PC
//! hooks around hand-assembled sequences, and the remaining exception-model cases: WFE with
//! SEVONPEND, BKPT without a debugger, execute-never, booting from another vector table,
//! a reset the bus requests.
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

mod common;
use common::*;
use m4_sim::{Config, Reg, ResetCause, Stop};

/// Cycles of `seq` (zero-wait-state memory): the program is `nop; seq; bkpt`, measured
/// from the first instruction of `seq` to the BKPT.
fn cycles(seq: &[u16], regs: &[(u8, u32)], fpu: bool) -> u64 {
    let mut code = vec![0xBF00];
    code.extend_from_slice(seq);
    let mut rig = Rig::new(&code);
    if fpu {
        rig.scs_write(0xE000_ED88, 0xF << 20);
        rig.cpu.write_reg(Reg::Control, 4);
    }
    for &(r, v) in regs {
        rig.set(r, v);
    }
    let (start, end) = (CODE + 2, CODE + 2 * code.len() as u32);
    rig.cpu.add_pc_hook(start);
    rig.cpu.add_pc_hook(end);
    assert_eq!(rig.run(), Stop::Hook { pc: start });
    let c0 = rig.cpu.cycles();
    assert_eq!(rig.run(), Stop::Hook { pc: end });
    rig.cpu.cycles() - c0
}

#[test]
fn alu_instructions_take_one_cycle() {
    const SEQ: &[u16] = &[
        // asm: alu4
        0x1888, // 00: adds r0, r1, r2
        0x1888, // 02: adds r0, r1, r2
        0xEA84, 0x0305, // 04: eor.w r3, r4, r5
        0x463E, // 08: mov r6, r7
    ];
    assert_eq!(cycles(SEQ, &[], false), 4);
}

#[test]
fn loads_take_two_and_pipeline_unless_dependent() {
    const PIPELINED: &[u16] = &[
        // asm: loads_pipelined
        0x6808, // 00: ldr r0, [r1]
        0x681A, // 02: ldr r2, [r3]
    ];
    assert_eq!(cycles(PIPELINED, &[(1, DATA), (3, DATA)], false), 3);
    const DEPENDENT: &[u16] = &[
        // asm: loads_dependent
        0x6808, // 00: ldr r0, [r1]
        0x6802, // 02: ldr r2, [r0]
    ];
    assert_eq!(cycles(DEPENDENT, &[(1, DATA)], false), 4);
    const STORE: &[u16] = &[
        // asm: store
        0x6008, // 00: str r0, [r1]
    ];
    assert_eq!(cycles(STORE, &[(1, DATA)], false), 1);
}

#[test]
fn taken_branches_refill_the_pipeline() {
    const TAKEN: &[u16] = &[
        // asm: branch
        0xE000, // 00: b 0x4 <.text+0x4> @ imm = #0x0
        0xBF00, // 02: nop
        0xBF00, // 04: nop
    ];
    // B (1) + refill (2) + the NOP at the target (1).
    assert_eq!(cycles(TAKEN, &[], false), 4);
    const NOT_TAKEN: &[u16] = &[
        // asm: branch_not_taken
        0xD000, // 00: beq 0x4 <.text+0x4> @ imm = #0x0
        0xBF00, // 02: nop
        0xBF00, // 04: nop
    ];
    // Z clear: falls through the two NOPs.
    assert_eq!(cycles(NOT_TAKEN, &[], false), 3);
}

#[test]
fn multiple_transfers_take_one_plus_n() {
    const PUSH: &[u16] = &[
        // asm: push
        0xB5F0, // 00: push {r4, r5, r6, r7, lr}
    ];
    assert_eq!(cycles(PUSH, &[], false), 6);
}

#[test]
fn division_terminates_early() {
    const UDIV: &[u16] = &[
        // asm: udiv
        0xFBB1, 0xF0F2, // 00: udiv r0, r1, r2
    ];
    // 100 / 7: a 5-bit quotient, 4 + ⌈5/4⌉.
    assert_eq!(cycles(UDIV, &[(1, 100), (2, 7)], false), 6);
    assert_eq!(cycles(UDIV, &[(1, 3), (2, 7)], false), 2);
    assert_eq!(cycles(UDIV, &[(1, u32::MAX), (2, 1)], false), 12);
}

#[test]
fn fpu_latencies() {
    const FP: &[u16] = &[
        // asm: fp
        0xEE30, 0x0A81, // 00: vadd.f32 s0, s1, s2
        0xEE42, 0x1A22, // 04: vmla.f32 s3, s4, s5
        0xEE83, 0x3A84, // 08: vdiv.f32 s6, s7, s8
    ];
    assert_eq!(cycles(FP, &[], true), 1 + 3 + 14);
}

#[test]
fn sev_sets_the_event_wfe_consumes() {
    const CODE: &[u16] = &[
        // asm: more_ext
        0xBF40, // 00: sev
        0xBF20, // 02: wfe
        0x2001, // 04: movs r0, #0x1
    ];
    let mut rig = Rig::new(CODE);
    rig.run_to_end(CODE.len());
    assert!(!rig.cpu.is_sleeping());
}

#[test]
fn sevonpend_wakes_wfe_for_a_disabled_interrupt() {
    // wfe; movs r0, #1; bkpt — the interrupt is pending but not enabled.
    let mut rig = Rig::new(&[0xBF20, 0x2001]);
    rig.scs_write(0xE000_ED10, 1 << 4);
    assert_eq!(rig.cpu.run_until(&mut rig.bus, 1_000_000), Stop::Deadline);
    assert!(rig.cpu.is_sleeping());
    rig.bus.irq[0] = 1;
    assert_eq!(
        rig.run(),
        Stop::Breakpoint {
            pc: CODE + 4,
            imm: 0
        }
    );
    assert_eq!(rig.r(0), 1);
}

#[test]
fn without_a_debugger_bkpt_is_a_hard_fault() {
    const CODE: &[u16] = &[
        // asm: bkpt_nohalt
        0xBE03, // 00: bkpt #0x3
    ];
    let cfg = Config {
        halt_on_bkpt: false,
        ..Config::default()
    };
    let mut rig = Rig::with_config(cfg, CODE);
    // The HardFault handler's own BKPT is a fault in HardFault: lockup.
    assert_eq!(
        rig.run(),
        Stop::Lockup {
            pc: default_handler(3)
        }
    );
    assert_eq!(rig.cpu.exceptions_taken()[3], 1);
}

#[test]
fn executing_from_the_system_region_is_a_memmanage_fault() {
    const CODE: &[u16] = &[
        // asm: xn
        0x4700, // 00: bx r0
    ];
    let mut rig = Rig::new(CODE);
    rig.scs_write(0xE000_ED24, 1 << 16);
    rig.set(0, 0xE000_0001);
    rig.run_to_handler(4);
    assert_eq!(rig.scs_read(0xE000_ED28), 1, "MMFSR.IACCVIOL");
}

#[test]
fn boot_starts_from_another_vector_table() {
    let mut rig = Rig::new(&[0xBF00]);
    // A second table at 0x1000: SP 0x2000_4000, reset at 0x1101 (a BKPT #9).
    rig.poke(0x1000, 0x2000_4000);
    rig.poke(0x1004, 0x1101);
    rig.place(0x1100, &[0xBE09]);
    rig.cpu.boot(&mut rig.bus, 0x1000);
    assert_eq!(rig.run(), Stop::Breakpoint { pc: 0x1100, imm: 9 });
    assert_eq!(rig.r(13), 0x2000_4000);
    assert_eq!(rig.scs_read(0xE000_ED08), 0x1000, "VTOR");
}

#[test]
fn a_reset_the_bus_requests_restarts_the_core() {
    let mut rig = Rig::new(&[0xE7FE]); // b .
    rig.set(5, 55);
    assert_eq!(rig.cpu.run_until(&mut rig.bus, 1_000_000), Stop::Deadline);
    rig.bus.reset_request = Some(ResetCause::Watchdog);
    rig.bus.next_event = 1_500_000;
    assert_eq!(rig.cpu.run_until(&mut rig.bus, 2_000_000), Stop::Deadline);
    assert_eq!(rig.r(5), 0);
    assert_eq!(rig.cpu.read_reg(Reg::R(15)), CODE);
}

#[test]
fn the_bus_is_advanced_to_each_event_and_to_the_deadline() {
    let mut rig = Rig::new(&[0xE7FE]);
    rig.bus.next_event = 300_000;
    assert_eq!(rig.cpu.run_until(&mut rig.bus, 1_000_000), Stop::Deadline);
    let advanced = &rig.bus.advanced;
    assert!(
        advanced.iter().any(|&t| (300_000..300_200).contains(&t)),
        "{advanced:?}"
    );
    assert!(advanced.last().is_some_and(|&t| t >= 1_000_000));
}

/// A flat bus with a clock register at 0x4000_0000: writing it sets the core clock.
struct ClockBus(m4_sim::FlatBus);

impl m4_sim::Bus for ClockBus {
    fn fetch(&mut self, addr: u32) -> Option<u16> {
        self.0.fetch(addr)
    }
    fn read(&mut self, addr: u32, w: m4_sim::Width, now: u64) -> Result<u32, m4_sim::BusFault> {
        self.0.read(addr, w, now)
    }
    fn write(
        &mut self,
        addr: u32,
        w: m4_sim::Width,
        v: u32,
        now: u64,
    ) -> Result<(), m4_sim::BusFault> {
        if addr == 0x4000_0000 {
            self.0.set_hz(v);
            return Ok(());
        }
        self.0.write(addr, w, v, now)
    }
    fn code_generation(&self) -> u64 {
        self.0.code_generation()
    }
    fn irq_lines(&self) -> [u32; 8] {
        self.0.irq
    }
    fn next_event_ns(&self) -> u64 {
        self.0.next_event
    }
    fn advance(&mut self, now: u64) {
        self.0.advance(now);
    }
    fn core_hz(&self) -> u32 {
        self.0.core_hz()
    }
}

#[test]
fn a_clock_change_inside_a_run_moves_the_deadline_in_cycles() {
    // str r1, [r0] (the clock register); b .
    let rig = Rig::new(&[0x6001, 0xE7FE]);
    let mut cpu = rig.cpu;
    let mut bus = ClockBus(rig.bus);
    cpu.write_reg(Reg::R(0), 0x4000_0000);
    cpu.write_reg(Reg::R(1), 100_000_000);
    assert_eq!(cpu.run_until(&mut bus, 1_000_000), Stop::Deadline);
    // A few cycles at 25 MHz, the rest of the millisecond at 100 MHz.
    assert!(
        (1_000_000..1_000_030).contains(&cpu.now_ns()),
        "{}",
        cpu.now_ns()
    );
    assert!(
        (99_800..100_010).contains(&cpu.cycles()),
        "{}",
        cpu.cycles()
    );
}

#[test]
fn basepri_max_only_raises_the_priority() {
    // msr basepri_max, r0/r1/r2; mrs r3, basepri
    let code = [
        0xF380, 0x8812, 0xF381, 0x8812, 0xF382, 0x8812, 0xF3EF, 0x8311,
    ];
    let mut rig = Rig::new(&code);
    rig.set(0, 0x80);
    rig.set(1, 0xC0); // lower priority than 0x80: ignored
    rig.set(2, 0x40);
    rig.run_to_end(code.len());
    assert_eq!(rig.r(3), 0x40);
}

#[test]
fn sleep_on_exit_returns_to_sleep_after_the_handler() {
    // wfi; movs r7, #7 — with SLEEPONEXIT the thread does not get past the WFI: the
    // handler (which disables its interrupt) returns into sleep.
    let mut rig = Rig::new(&[0xBF30, 0x2707]);
    let m = mov32(0, 0xE000_E180); // ICER0
    rig.place(0x400, &[m[0], m[1], m[2], m[3], 0x2101, 0x6001, 0x4770]);
    rig.vector(16, 0x400);
    rig.scs_write(0xE000_ED10, 1 << 1);
    rig.scs_write(0xE000_E100, 1);
    assert_eq!(rig.cpu.run_until(&mut rig.bus, 1_000_000), Stop::Deadline);
    assert!(rig.cpu.is_sleeping());
    rig.bus.irq[0] = 1;
    assert_eq!(rig.cpu.run_until(&mut rig.bus, 2_000_000), Stop::Deadline);
    assert_eq!(rig.cpu.exceptions_taken()[16], 1);
    assert!(rig.cpu.is_sleeping());
    assert_eq!(rig.r(7), 0);
}
