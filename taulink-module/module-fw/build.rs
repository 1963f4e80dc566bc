//! The nRF52840 image's memory layouts, one chosen by feature; writing it to OUT_DIR and the
//! link arguments are `fw-link`'s (hardware/fw-link, shared with flight-fw). Host builds (the
//! stub `main`) get nothing.

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
    fw_link::link_image(if fw_link::feature("uf2") { UF2 } else { PROBE });
}
