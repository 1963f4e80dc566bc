//! Processor in the loop: the images a pilot flashes, run on emulated microcontrollers
//! (`m4-sim`'s Cortex-M4F core with this crate's register-level STM32F405 and nRF52840
//! peripheral models) against the project's simulated chips, handset and quadrotor.
//!
//! - [`stm32f405`]: the flight images' STM32F405, register by register (its README says
//!   what is modelled, the cycle model and the datasheet figures).
//! - [`wire`]: what a microcontroller model sees of its board — pins, SPI, I²C, UART and
//!   analog inputs — the one boundary between the SoC models and the world.

pub mod stm32f405;
pub mod wire;
