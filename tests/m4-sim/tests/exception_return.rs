//! An interrupt handler that returns with `pop {…, pc}` (as every compiled handler does)
//! resumes the interrupted code at its next instruction (ARMv7-M ARM B1.5.8,
//! ExceptionReturn: the PC comes from the stacked frame). Found running the flight image:
//! the first TIM2 interrupt returned to the instruction after its handler's `pop`.
#![allow(clippy::unwrap_used)]

use m4_sim::{Config, Cpu, FlatBus, Reg, Stop};

fn halves(v: &[u16]) -> Vec<u8> {
    v.iter().flat_map(|h| h.to_le_bytes()).collect()
}

#[test]
fn a_handler_popping_the_pc_returns_to_the_interrupted_code() {
    let mut bus = FlatBus::mps2_an386();
    // Vector table: SP, reset at 0x100, IRQ 0 (exception 16) at 0x200.
    bus.load(0, &0x2000_1000u32.to_le_bytes());
    bus.load(4, &0x0000_0101u32.to_le_bytes());
    bus.load(0x40, &0x0000_0201u32.to_le_bytes());
    // ldr r0, =NVIC_ISER0; movs r1, #1; str r1, [r0]; ldr r0, =NVIC_ISPR0; str r1, [r0]
    // (IRQ 0 pends and is taken here); movs r0, #42; bkpt #0.
    bus.load(
        0x100,
        &halves(&[
            0x4804, 0x2101, 0x6001, 0x4804, 0x6001, 0x202A, 0xBE00, 0xBF00, 0xBF00, 0xBF00,
        ]),
    );
    bus.load(0x114, &0xE000_E100u32.to_le_bytes());
    bus.load(0x118, &0xE000_E200u32.to_le_bytes());
    // Handler: push {r4, lr}; movs r4, #7; pop {r4, pc}.
    bus.load(0x200, &halves(&[0xB510, 0x2407, 0xBD10, 0xDEFE]));
    let mut cpu = Cpu::new(Config::default());
    cpu.reset(&mut bus);
    let stop = cpu.run_until(&mut bus, 1_000_000);
    assert_eq!(stop, Stop::Breakpoint { pc: 0x10C, imm: 0 });
    assert_eq!(cpu.read_reg(Reg::R(0)), 42);
    assert_eq!(
        cpu.read_reg(Reg::R(4)),
        0,
        "r4 restored by the handler's pop"
    );
    assert_eq!(cpu.read_reg(Reg::Xpsr) & 0x1FF, 0, "back in Thread mode");
    assert_eq!(cpu.read_reg(Reg::Msp), 0x2000_1000, "the frame unstacked");
}
