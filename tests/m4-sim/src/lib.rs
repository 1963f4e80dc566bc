//! A Cortex-M4F emulator: the ARMv7E-M instruction set (Thumb, Thumb-2, the DSP extension and
//! FPv4-SP), the exception model (NVIC, SCB, SysTick, priorities, stacking, tail-chaining,
//! faults), WFI/WFE as "advance time", and a cycle model, on virtual time. Everything outside
//! the core — memories and peripherals — is a [`Bus`], supplied by a SoC model
//! (`tests/pil`), so the same core runs an STM32F405 or an nRF52840 image.
//!
//! Written for this project (no emulator code is linked in; see `tests/pil/README.md` for why).

pub mod bus;

pub use bus::{Bus, BusFault, Width};
