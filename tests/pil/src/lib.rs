//! Processor in the loop: the images a pilot flashes, run on emulated microcontrollers
//! (`m4-sim`'s Cortex-M4F core with this crate's register-level STM32F405 and nRF52840
//! peripheral models) against the project's simulated chips, handset and quadrotor.
//!
//! - [`wire`]: what a microcontroller model sees of its board — pins, SPI, I²C, UART and
//!   analog inputs — the one boundary between the SoC models and the world.
//! - [`nrf52840`]: the module's nRF52840, register by register.
//! - [`stm32f405`]: the flight controller's STM32F405, register by register.
//! - [`chips`]: the chips on the boards, register by register from their datasheets.
//! - [`board`]: the boards (which chip is on which pin), each an `Outside`.
//! - [`world`]: the co-simulation of both MCUs with the radios, physics, handset and pilot.

pub mod board;
pub mod chips;
pub mod nrf52840;
pub mod runner;
pub mod stm32f405;
pub mod wire;
pub mod world;
