//! A Cortex-M4F emulator: the ARMv7E-M instruction set (Thumb, Thumb-2, the DSP extension and
//! FPv4-SP), the exception model (NVIC, SCB, SysTick, priorities, stacking, tail-chaining,
//! faults), WFI/WFE as "advance time", and a cycle model, on virtual time. Everything outside
//! the core — memories and peripherals — is a [`Bus`], supplied by a SoC model
//! (`tests/pil`), so the same core runs an STM32F405 or an nRF52840 image.
//!
//! ```
//! use m4_sim::{Config, Cpu, FlatBus, Stop};
//!
//! // A vector table (SP, reset vector) and `movs r0, #42; bkpt #0` at 0x100.
//! let mut bus = FlatBus::mps2_an386();
//! bus.load(0, &[0x00, 0x10, 0x00, 0x20, 0x01, 0x01, 0x00, 0x00]);
//! bus.load(0x100, &[0x2A, 0x20, 0x00, 0xBE]);
//! let mut cpu = Cpu::new(Config::default());
//! cpu.reset(&mut bus);
//! let stop = cpu.run_until(&mut bus, 1_000_000);
//! assert_eq!(stop, Stop::Breakpoint { pc: 0x102, imm: 0 });
//! assert_eq!(cpu.read_reg(m4_sim::Reg::R(0)), 42);
//! ```
//!
//! Written for this project from the Arm architecture and processor manuals; no emulator
//! code is linked in (the crate README says why and what is modelled).

mod access;
pub mod bus;
mod cache;
mod clock;
mod config;
mod cpu;
mod cycles;
pub mod decode;
mod exception;
mod exec;
mod fault;
pub mod flatbus;
mod insn;
mod nvic;
mod regs;
mod scs;
mod semihost;
mod softfloat;
mod systick;

pub use bus::{Bus, BusFault, ResetCause, Width};
pub use config::Config;
pub use cpu::{Cpu, FaultStatus, Reg, Stats, Stop};
pub use flatbus::FlatBus;
