//! The exception model: stacking and EXC_RETURN, frame alignment, the process stack, the
//! FP frame, masking by PRIMASK and BASEPRI, preemption, tail-chaining, PendSV, SysTick,
//! sleeping with WFI and WFE, faults and their escalation, lockup, system reset and
//! semihosting (ARMv7-M ARM B1.5).
#![allow(clippy::unwrap_used, clippy::indexing_slicing)]

mod common;
use common::*;
use m4_sim::{Bus, BusFault, Config, Cpu, FlatBus, Reg, Stop, Width};

const HANDLER: u32 = 0x400;
const HANDLER2: u32 = 0x480;
const SVCALL: u32 = 11;

const HANDLER_CODE: &[u16] = &[
    // asm: handler
    0x4674, // 00: mov r4, lr
    0x466D, // 02: mov r5, sp
    0xF3EF, 0x8605, // 04: mrs r6, ipsr
    0x4770, // 08: bx lr
];

#[test]
fn svc_stacks_a_frame_and_returns_past_the_svc() {
    const CODE: &[u16] = &[
        // asm: svc
        0x200A, // 00: movs r0, #0xa
        0x210B, // 02: movs r1, #0xb
        0x220C, // 04: movs r2, #0xc
        0x230D, // 06: movs r3, #0xd
        0x469C, // 08: mov r12, r3
        0xDF05, // 0a: svc #0x5
        0x3001, // 0c: adds r0, #0x1
    ];
    let mut rig = Rig::new(CODE);
    rig.place(HANDLER, HANDLER_CODE);
    rig.vector(SVCALL, HANDLER);
    rig.set(14, 0x1234_5679);
    rig.run_to_end(CODE.len());
    assert_eq!(
        rig.r(4),
        0xFFFF_FFF9,
        "EXC_RETURN: thread mode, main stack, no FP"
    );
    assert_eq!(rig.r(6), SVCALL);
    let frame = rig.r(5);
    assert_eq!(frame, STACK - 32);
    let words: Vec<u32> = (0..8).map(|i| rig.word(frame + 4 * i)).collect();
    assert_eq!(&words[..6], &[10, 11, 12, 13, 13, 0x1234_5679]);
    assert_eq!(
        words[6],
        CODE_AT + 12,
        "return address: the instruction after SVC"
    );
    assert_eq!(words[7] & (1 << 24), 1 << 24, "stacked T bit");
    assert_eq!(rig.r(0), 11, "execution resumed after the SVC");
    assert_eq!(rig.r(13), STACK);
    assert_eq!(rig.cpu.exceptions_taken()[SVCALL as usize], 1);
}

const CODE_AT: u32 = CODE;

#[test]
fn an_unaligned_stack_is_realigned_and_restored() {
    const CODE: &[u16] = &[
        // asm: svc
        0x200A, // 00: movs r0, #0xa
        0x210B, // 02: movs r1, #0xb
        0x220C, // 04: movs r2, #0xc
        0x230D, // 06: movs r3, #0xd
        0x469C, // 08: mov r12, r3
        0xDF05, // 0a: svc #0x5
        0x3001, // 0c: adds r0, #0x1
    ];
    let mut rig = Rig::new(CODE);
    rig.place(HANDLER, HANDLER_CODE);
    rig.vector(SVCALL, HANDLER);
    rig.set(13, STACK - 4);
    rig.run_to_end(CODE.len());
    let frame = rig.r(5);
    assert_eq!(frame, (STACK - 4 - 32) & !7);
    assert_ne!(
        rig.word(frame + 28) & (1 << 9),
        0,
        "xPSR bit 9 records the realignment"
    );
    assert_eq!(rig.r(13), STACK - 4);
}

#[test]
fn thread_mode_on_the_process_stack() {
    const CODE: &[u16] = &[
        // asm: psp_thread
        0xF380, 0x8809, // 00: msr psp, r0
        0x2102, // 04: movs r1, #0x2
        0xF381, 0x8814, // 06: msr control, r1
        0xF3BF, 0x8F6F, // 0a: isb sy
        0xDF00, // 0e: svc #0x0
        0xF3EF, 0x8714, // 10: mrs r7, control
    ];
    let mut rig = Rig::new(CODE);
    rig.place(HANDLER, HANDLER_CODE);
    rig.vector(SVCALL, HANDLER);
    rig.set(0, 0x2000_4000);
    rig.run_to_end(CODE.len());
    assert_eq!(
        rig.r(4),
        0xFFFF_FFFD,
        "EXC_RETURN: thread mode, process stack"
    );
    assert_eq!(rig.r(5), STACK, "the handler runs on the main stack");
    assert_eq!(rig.cpu.read_reg(Reg::Psp), 0x2000_4000);
    assert_eq!(rig.r(7), 2, "SPSEL still set after the return");
    assert_eq!(
        rig.word(0x2000_4000 - 32),
        0x2000_4000,
        "R0 stacked on the process stack"
    );
}

#[test]
fn an_active_fp_context_gets_the_extended_frame() {
    const CODE: &[u16] = &[
        // asm: fp_thread
        0xEEB7, 0x0A00, // 00: vmov.f32 s0, #1.000000e+00
        0xDF00, // 04: svc #0x0
        0xEE10, 0x7A10, // 06: vmov r7, s0
    ];
    const FP_HANDLER: &[u16] = &[
        // asm: fp_handler
        0x4674, // 00: mov r4, lr
        0x466D, // 02: mov r5, sp
        0xEEB0, 0x0A00, // 04: vmov.f32 s0, #2.000000e+00
        0x4770, // 08: bx lr
    ];
    let mut rig = Rig::new(CODE);
    rig.scs_write(0xE000_ED88, 0xF << 20);
    rig.place(HANDLER, FP_HANDLER);
    rig.vector(SVCALL, HANDLER);
    rig.run_to_end(CODE.len());
    assert_eq!(
        rig.r(4),
        0xFFFF_FFE9,
        "EXC_RETURN with bit 4 clear: FP frame"
    );
    assert_eq!(rig.r(5), STACK - 0x68);
    assert_eq!(rig.word(STACK - 0x68 + 0x20), 1f32.to_bits(), "S0 stacked");
    assert_eq!(rig.r(7), 1f32.to_bits(), "S0 restored on return");
}

#[test]
fn primask_holds_an_interrupt_until_cpsie() {
    const CODE: &[u16] = &[
        // asm: cps
        0xB672, // 00: cpsid i
        0xBF00, // 02: nop
        0xBF00, // 04: nop
        0xB662, // 06: cpsie i
        0xBF00, // 08: nop
    ];
    let mut rig = Rig::new(CODE);
    rig.scs_write(0xE000_E100, 1); // ISER0: IRQ 0
    rig.cpu.write_reg(Reg::Primask, 1);
    rig.bus.irq[0] = 1;
    rig.run_to_handler(16);
    // Taken right after CPSIE: the frame returns to the NOP after it.
    assert_eq!(rig.word(rig.r(13) + 24), CODE_AT + 8);
}

#[test]
fn basepri_masks_lower_priorities_only() {
    const CODE: &[u16] = &[
        // asm: basepri
        0xF380, 0x8811, // 00: msr basepri, r0
        0xBF00, // 04: nop
        0xBF00, // 06: nop
    ];
    for (prio, taken) in [(0x80u32, false), (0x20, true)] {
        let mut rig = Rig::new(CODE);
        rig.scs_write(0xE000_E100, 1);
        rig.scs_write(0xE000_E400, prio);
        rig.set(0, 0x40);
        rig.cpu.write_reg(Reg::Basepri, 0x40);
        rig.bus.irq[0] = 1;
        let stop = rig.run();
        if taken {
            assert_eq!(
                stop,
                Stop::Breakpoint {
                    pc: default_handler(16),
                    imm: 16
                }
            );
        } else {
            assert_eq!(
                stop,
                Stop::Breakpoint {
                    pc: CODE_AT + 2 * CODE.len() as u32,
                    imm: 0
                }
            );
        }
    }
}

#[test]
fn a_higher_priority_interrupt_preempts_a_handler() {
    const LOW: &[u16] = &[
        // asm: nested_irq_low
        0x4674, // 00: mov r4, lr
        0x6001, // 02: str r1, [r0]
        0x4675, // 04: mov r5, lr
        0x4770, // 06: bx lr
    ];
    const HIGH: &[u16] = &[
        // asm: nested_irq_high
        0x4676, // 00: mov r6, lr
        0xF3EF, 0x8705, // 02: mrs r7, ipsr
        0x4770, // 06: bx lr
    ];
    let mut rig = Rig::new(&[0xBF00]); // nop
    rig.place(HANDLER, LOW);
    rig.place(HANDLER2, HIGH);
    rig.vector(16, HANDLER);
    rig.vector(17, HANDLER2);
    rig.scs_write(0xE000_E100, 3);
    rig.scs_write(0xE000_E400, 0x0000_2080); // IRQ0 0x80, IRQ1 0x20
    rig.set(0, 0xE000_EF00); // STIR
    rig.set(1, 1); // pend IRQ 1 from inside IRQ 0's handler
    rig.scs_write(0xE000_E200, 1); // ISPR0: IRQ 0 pending
    let stop = rig.run();
    assert!(matches!(stop, Stop::Breakpoint { .. }), "{stop:?}");
    assert_eq!(rig.r(4), 0xFFFF_FFF9);
    assert_eq!(rig.r(6), 0xFFFF_FFF1, "nested: return to handler mode");
    assert_eq!(rig.r(7), 17);
    assert_eq!(
        rig.r(5),
        0xFFFF_FFF9,
        "the low handler's LR survived the preemption"
    );
}

#[test]
fn an_equal_priority_interrupt_tail_chains() {
    const A: &[u16] = &[
        // asm: tail_a
        0x466C, // 00: mov r4, sp
        0x6001, // 02: str r1, [r0]
        0x4770, // 04: bx lr
    ];
    const B: &[u16] = &[
        // asm: tail_b
        0x466D, // 00: mov r5, sp
        0x4676, // 02: mov r6, lr
        0x4770, // 04: bx lr
    ];
    let mut rig = Rig::new(&[0xBF00]);
    rig.place(HANDLER, A);
    rig.place(HANDLER2, B);
    rig.vector(16, HANDLER);
    rig.vector(17, HANDLER2);
    rig.scs_write(0xE000_E100, 3);
    rig.set(0, 0xE000_E200); // ISPR0
    rig.set(1, 2); // pend IRQ 1 (same priority: it cannot preempt)
    rig.scs_write(0xE000_E200, 1);
    let before = rig.cpu.cycles();
    rig.run_to_end(1);
    assert_eq!(
        rig.r(5),
        rig.r(4),
        "B ran on A's frame: no unstacking in between"
    );
    assert_eq!(rig.r(6), 0xFFFF_FFF9, "B returns straight to thread mode");
    assert_eq!(rig.cpu.exceptions_taken()[16], 1);
    assert_eq!(rig.cpu.exceptions_taken()[17], 1);
    // Entry 12 + A (4) + tail-chain 6 + B (4) + return 10 + the rest: far below two full
    // entries and returns.
    assert!(
        rig.cpu.cycles() - before < 60,
        "{}",
        rig.cpu.cycles() - before
    );
}

#[test]
fn pendsv_is_set_pending_through_icsr() {
    const CODE: &[u16] = &[
        // asm: pendsv
        0x6001, // 00: str r1, [r0]
        0xBF00, // 02: nop
    ];
    const READ_ICSR: &[u16] = &[
        // asm: icsr_read
        0x6807, // 00: ldr r7, [r0]
        0x4770, // 02: bx lr
    ];
    let mut rig = Rig::new(CODE);
    rig.place(HANDLER, READ_ICSR);
    rig.vector(14, HANDLER);
    rig.set(0, 0xE000_ED04);
    rig.set(1, 1 << 28);
    rig.run_to_end(CODE.len());
    assert_eq!(rig.r(7) & 0x1FF, 14, "VECTACTIVE");
    assert_ne!(rig.r(7) & (1 << 11), 0, "RETTOBASE");
}

#[test]
fn systick_interrupts_every_period() {
    const CODE: &[u16] = &[
        // asm: systick_setup
        0x6041, // 00: str r1, [r0, #0x4]
        0x6082, // 02: str r2, [r0, #0x8]
        0x6003, // 04: str r3, [r0]
        0xBF30, // 06: wfi
        0xE7FD, // 08: b 0x6 <.text+0x6> @ imm = #-0x6
    ];
    let mut rig = Rig::new(CODE);
    rig.set(0, 0xE000_E010);
    rig.set(1, 999); // RVR
    rig.set(2, 0); // CVR
    rig.set(3, 7); // enable, interrupt, processor clock
    rig.run_to_handler(15);
    let t = rig.cpu.cycles();
    // Enabled a few cycles in; wraps 1000 cycles later; 12 cycles of entry, the BKPT.
    assert!((1012..1030).contains(&t), "{t}");
    assert!(rig.cpu.stats().cycles_asleep > 900);
}

/// A bus whose interrupt line 0 rises at a set time.
struct TimerBus {
    flat: FlatBus,
    at_ns: u64,
}

impl Bus for TimerBus {
    fn fetch(&mut self, addr: u32) -> Option<u16> {
        self.flat.fetch(addr)
    }
    fn read(&mut self, addr: u32, width: Width, now_ns: u64) -> Result<u32, BusFault> {
        self.flat.read(addr, width, now_ns)
    }
    fn write(&mut self, addr: u32, width: Width, value: u32, now_ns: u64) -> Result<(), BusFault> {
        self.flat.write(addr, width, value, now_ns)
    }
    fn code_generation(&self) -> u64 {
        self.flat.code_generation()
    }
    fn irq_lines(&self) -> [u32; 8] {
        self.flat.irq
    }
    fn next_event_ns(&self) -> u64 {
        self.at_ns
    }
    fn advance(&mut self, now_ns: u64) {
        if now_ns >= self.at_ns {
            self.flat.irq[0] = 1;
            self.at_ns = u64::MAX;
        }
    }
    fn core_hz(&self) -> u32 {
        self.flat.core_hz()
    }
}

#[test]
fn wfi_sleeps_until_the_next_event_in_one_jump() {
    const CODE: &[u16] = &[
        // asm: wfi_loop
        0xBF30, // 00: wfi
        0x3701, // 02: adds r7, #0x1
    ];
    let rig = Rig::new(CODE);
    let mut cpu = rig.cpu;
    let mut bus = TimerBus {
        flat: rig.bus,
        at_ns: 3_000_000,
    };
    // Enable IRQ 0 with PRIMASK set: WFI still wakes, the handler waits for CPSIE.
    cpu.write_reg(Reg::Primask, 1);
    bus.flat
        .load(0x600, &[0x4F, 0xF0, 0x01, 0x00, 0xC4, 0xF2, 0x00, 0x00]);
    let mut cpu = enable_irq0(cpu, &mut bus);
    let stop = cpu.run_until(&mut bus, 10_000_000);
    assert_eq!(
        stop,
        Stop::Breakpoint {
            pc: CODE_AT + 4,
            imm: 0
        }
    );
    assert_eq!(cpu.read_reg(Reg::R(7)), 1);
    // Woken at 3 ms: 75 000 cycles of 25 MHz, nearly all asleep.
    assert!(
        cpu.now_ns() >= 3_000_000 && cpu.now_ns() < 3_001_000,
        "{}",
        cpu.now_ns()
    );
    assert!(cpu.stats().cycles_asleep >= 74_990);
    assert!(cpu.stats().instructions < 30);
    assert_eq!(
        cpu.exceptions_taken()[16],
        0,
        "PRIMASK held the interrupt back"
    );
}

/// Sets ISER0 bit 0 by running a store through the core.
fn enable_irq0(mut cpu: Cpu, bus: &mut TimerBus) -> Cpu {
    let pc = cpu.read_reg(Reg::R(15));
    let code: [u16; 7] = {
        let m = mov32(0, 0xE000_E100);
        [m[0], m[1], m[2], m[3], 0x2101, 0x6001, 0xBE00] // movs r1,#1; str r1,[r0]; bkpt
    };
    let bytes: Vec<u8> = code.iter().flat_map(|h| h.to_le_bytes()).collect();
    bus.flat.load(0x600, &bytes);
    cpu.write_reg(Reg::R(15), 0x600);
    assert!(matches!(cpu.run_until(bus, 1000), Stop::Breakpoint { .. }));
    cpu.write_reg(Reg::R(15), pc);
    cpu.write_reg(Reg::R(0), 0);
    cpu.write_reg(Reg::R(1), 0);
    cpu
}

#[test]
fn wfe_consumes_the_event_then_sleeps() {
    const CODE: &[u16] = &[
        // asm: wfe_twice
        0xBF40, // 00: sev
        0xBF20, // 02: wfe
        0xBF20, // 04: wfe
    ];
    let mut rig = Rig::new(CODE);
    assert_eq!(rig.cpu.run_until(&mut rig.bus, 5_000_000), Stop::Deadline);
    assert!(rig.cpu.is_sleeping());
    assert_eq!(rig.cpu.read_reg(Reg::R(15)), CODE_AT + 6);
    assert_eq!(rig.cpu.now_ns(), 5_000_000);
    assert_eq!(rig.cpu.stats().instructions, 3);
}

#[test]
fn a_bus_error_is_a_precise_bus_fault() {
    const CODE: &[u16] = &[
        // asm: bad_load
        0x6801, // 00: ldr r1, [r0]
    ];
    let mut rig = Rig::new(CODE);
    rig.scs_write(0xE000_ED24, 1 << 17); // BUSFAULTENA
    rig.set(0, 0x3000_0000);
    rig.run_to_handler(5);
    assert_eq!(
        rig.scs_read(0xE000_ED28),
        1 << 9 | 1 << 15,
        "PRECISERR, BFARVALID"
    );
    assert_eq!(rig.scs_read(0xE000_ED38), 0x3000_0000);
}

#[test]
fn interworking_to_arm_state_is_invstate() {
    const CODE: &[u16] = &[
        // asm: bx_even
        0x4700, // 00: bx r0
    ];
    let mut rig = Rig::new(CODE);
    rig.place(0x300, &[0xBF00]);
    rig.set(0, 0x300);
    rig.run_to_handler(3);
    assert_eq!(rig.scs_read(0xE000_ED28), 1 << 17);
    assert_eq!(
        rig.word(rig.r(13) + 24),
        0x300,
        "the fault returns to the target"
    );
    assert_eq!(rig.word(rig.r(13) + 28) & (1 << 24), 0, "with T clear");
}

#[test]
fn load_multiple_must_be_aligned() {
    const CODE: &[u16] = &[
        // asm: ldm_unaligned
        0xE890, 0x0006, // 00: ldm.w r0, {r1, r2}
    ];
    let mut rig = Rig::new(CODE);
    rig.scs_write(0xE000_ED24, 1 << 18);
    rig.set(0, DATA + 2);
    rig.run_to_handler(6);
    assert_eq!(rig.scs_read(0xE000_ED28), 1 << 24);
}

#[test]
fn a_fault_in_hardfault_locks_up() {
    const CODE: &[u16] = &[
        // asm: udf_in_handler
        0xDE01, // 00: udf #0x1
    ];
    let mut rig = Rig::new(CODE);
    rig.place(HANDLER, CODE);
    rig.vector(3, HANDLER);
    assert_eq!(rig.run(), Stop::Lockup { pc: HANDLER });
    assert!(rig.cpu.is_locked_up());
    // Locked up, time still passes (a watchdog could reset the chip).
    assert_eq!(
        rig.cpu.run_until(&mut rig.bus, 2_000_000_000),
        Stop::Deadline
    );
    assert_eq!(rig.cpu.now_ns(), 2_000_000_000);
}

#[test]
fn sysresetreq_resets_the_core() {
    const CODE: &[u16] = &[
        // asm: reset
        0x6001, // 00: str r1, [r0]
        0xF3BF, 0x8F4F, // 02: dsb sy
        0xE7FE, // 06: b 0x6 <.text+0x6> @ imm = #-0x4
    ];
    let mut rig = Rig::new(CODE);
    rig.set(0, 0xE000_ED0C);
    rig.set(1, 0x05FA_0004);
    rig.set(7, 77);
    rig.cpu.add_pc_hook(CODE_AT);
    assert_eq!(rig.run(), Stop::Hook { pc: CODE_AT });
    assert_eq!(rig.run(), Stop::Hook { pc: CODE_AT });
    assert_eq!(rig.r(7), 0, "registers reset");
    assert_eq!(rig.r(13), STACK);
}

#[test]
fn semihosting_writes_and_exits() {
    const CODE: &[u16] = &[
        // asm: semihost
        0x2004, // 00: movs r0, #0x4
        0xBEAB, // 02: bkpt #0xab
        0x2020, // 04: movs r0, #0x20
        0x4611, // 06: mov r1, r2
        0xBEAB, // 08: bkpt #0xab
    ];
    let mut rig = Rig::new(CODE);
    rig.bus.load(DATA, b"hello\0");
    rig.poke(DATA + 8, 0x2_0026);
    rig.poke(DATA + 12, 3);
    rig.set(1, DATA);
    rig.set(2, DATA + 8);
    assert_eq!(rig.run(), Stop::Exit { code: 3 });
    assert_eq!(rig.cpu.take_semihost_output(), b"hello");
}

#[test]
fn the_clock_rate_can_change_under_a_running_core() {
    let mut rig = Rig::new(&[0xE7FE]); // b .
    assert_eq!(rig.cpu.run_until(&mut rig.bus, 1_000_000), Stop::Deadline);
    // 1 ms at 25 MHz, to the first instruction boundary (a taken branch is 3 cycles).
    let c1 = rig.cpu.cycles();
    assert!((25_000..25_003).contains(&c1), "{c1}");
    // The bus reports a new clock after an advance.
    rig.bus.set_hz(100_000_000);
    assert_eq!(rig.cpu.run_until(&mut rig.bus, 2_000_000), Stop::Deadline);
    let ns_at_c1 = 1_000_000 + (c1 - 25_000) * 40;
    let expect = c1 + (2_000_000 - ns_at_c1) / 10;
    assert!(
        (expect..expect + 3).contains(&rig.cpu.cycles()),
        "{}",
        rig.cpu.cycles()
    );
    assert!((2_000_000..2_000_030).contains(&rig.cpu.now_ns()));
    let _ = Config::default();
}
