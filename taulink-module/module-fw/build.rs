//! Link setup for the nRF52840 image. Host builds (the stub `main`) get nothing.
//!
//! memory.x is chosen by feature and written to OUT_DIR, because the linker runs in the
//! workspace root and would not find one next to this file.

use std::{env, fs, path::PathBuf};

/// Flash 0x0–0xEBFFF for code, 0xEC000–0xF3FFF (8 pages of 4 KiB) for settings, and the top
/// 48 KiB left to a UF2 bootloader, so both layouts keep settings in the same place.
const PROBE: &str = "\
/* Flashed at 0x0 with a debug probe (no SoftDevice, no bootloader). */
MEMORY
{
  FLASH : ORIGIN = 0x00000000, LENGTH = 0xEC000
  RAM   : ORIGIN = 0x20000000, LENGTH = 256K
}
";

const UF2: &str = "\
/* Behind the Adafruit nRF52 UF2 bootloader (nice!nano): the MBR and the space of SoftDevice
   S140 v6 end at 0x26000. The bootloader does not leave the SoftDevice running, so all RAM
   is ours. */
MEMORY
{
  FLASH : ORIGIN = 0x00026000, LENGTH = 0xEC000 - 0x26000
  RAM   : ORIGIN = 0x20000000, LENGTH = 256K
}
";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let layout = if env::var_os("CARGO_FEATURE_UF2").is_some() {
        UF2
    } else {
        PROBE
    };
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap_or_default());
    if let Err(e) = fs::write(out.join("memory.x"), layout) {
        println!("cargo:warning=cannot write memory.x: {e}");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
