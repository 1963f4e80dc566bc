//! TauLink JR-bay module firmware for the nRF52840 (nice!nano-class boards).
//!
//! All behaviour lives in `module-core`; this crate only wires the board to it. On the host
//! it compiles to an empty program so that `cargo test --workspace` never builds a HAL.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware;

#[cfg(not(target_os = "none"))]
fn main() {}
