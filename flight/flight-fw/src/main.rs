//! TauLink flight firmware for the STM32F405 (BrushedSparky; Sparky2 with `--features sparky2`).
//!
//! All behaviour lives in `flight-core`; this crate only wires the board to it. On the host
//! it compiles to an empty program so that `cargo test --workspace` never builds a HAL.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware;

#[cfg(not(target_os = "none"))]
fn main() {}
