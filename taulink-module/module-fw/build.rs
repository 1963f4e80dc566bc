//! Link setup for the nRF52840 image. Host builds (the stub `main`) get nothing.
//!
//! memory.x is chosen by feature and written to OUT_DIR, because the linker runs in the
//! workspace root and would not find one next to this file.

use std::{env, fs, path::PathBuf};

/// Flash 0x0–0xE9FFF for code, 0xEC000–0xF3FFF (8 pages of 4 KiB) for settings, and the top
/// 48 KiB left to a UF2 bootloader, so both layouts keep settings in the same place. The
/// Adafruit bootloader keeps 10 pages below itself (0xEA000–0xF3FFF) for application data and
/// refuses UF2 blocks there, so code ends at 0xEA000 in both layouts.
const PROBE: &str = "\
/* Flashed at 0x0 with a debug probe (no SoftDevice, no bootloader). */
MEMORY
{
  FLASH : ORIGIN = 0x00000000, LENGTH = 0xEA000
  RAM   : ORIGIN = 0x20000000, LENGTH = 256K
}
";

const UF2: &str = "\
/* Behind the Adafruit nRF52 UF2 bootloader (nice!nano) with SoftDevice S140 v6 in flash: the
   MBR and the SoftDevice end at 0x26000; UF2 blocks are accepted up to 0xEA000. The
   SoftDevice is never enabled, but the MBR (and the disabled SoftDevice) forward interrupts
   through the first 8 bytes of RAM, so RAM starts at 0x20000008. The reset handler points
   VTOR at our own table (cortex-m-rt set-vtor), so interrupts do not depend on them. */
MEMORY
{
  FLASH : ORIGIN = 0x00026000, LENGTH = 0xEA000 - 0x26000
  RAM   : ORIGIN = 0x20000008, LENGTH = 256K - 8
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
