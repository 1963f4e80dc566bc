//! The boot contract of each image: where its bootloader (or the chip) starts it, what it
//! accepts, what it owns. `verify` checks the built files against these; the linker scripts
//! in the firmware crates' build.rs are the other side of the same contract.

use std::ops::Range;

/// What one image must satisfy to start behind its bootloader.
#[derive(Debug, Clone)]
pub struct Layout {
    /// Who starts the image (for messages and the README).
    pub starter: &'static str,
    /// Where the vector table must sit: the address the bootloader (or reset) starts from.
    pub origin: u32,
    /// Load addresses the bootloader or flash tool accepts.
    pub accepted: Range<u32>,
    /// Whether `accepted` is a bootloader's application partition, which an image must
    /// leave room in (`budget::PARTITION_PERCENT`); false where the chip's reset starts it.
    pub behind_bootloader: bool,
    /// Flash the image must not write: settings sectors, bootloader pages.
    pub reserved_flash: &'static [(Range<u32>, &'static str)],
    /// SRAM the image may use (statics and stack).
    pub ram: Range<u32>,
    /// The initial SP must pass `(sp & mask) == value` (the Tau Labs bootloader's check).
    pub sp_mask: Option<(u32, u32)>,
    /// UF2 family ID the bootloader insists on.
    pub uf2_family: Option<u32>,
}

/// STM32F405 flash sectors 2–3: settings in both flight layouts.
const F405_SETTINGS: (Range<u32>, &str) = (0x0800_8000..0x0801_0000, "settings (sectors 2-3)");
/// STM32F405 SRAM1+SRAM2.
const F405_RAM: Range<u32> = 0x2000_0000..0x2002_0000;
/// nRF52840 settings pages (module-fw board.rs `SETTINGS_FLASH`).
const NRF_SETTINGS: (Range<u32>, &str) = (0xEC000..0xF4000, "settings (8 pages)");

/// Flight image at 0x0800_0000: SWD probe or the ST ROM's USB DFU.
pub const F405_DIRECT: Layout = Layout {
    starter: "reset / ST ROM DFU",
    origin: 0x0800_0000,
    accepted: 0x0800_0000..0x0810_0000,
    behind_bootloader: false,
    reserved_flash: &[F405_SETTINGS],
    ram: F405_RAM,
    sp_mask: None,
    uf2_family: None,
};

/// Flight image behind the Tau Labs bootloader (sparky2 board-info.mk: BL bank 0x0800_0000
/// + 32 KiB, FW bank 0x0802_0000 + 384 KiB with the 100-byte descriptor at its end).
pub const F405_TAULABS: Layout = Layout {
    starter: "Tau Labs bootloader",
    origin: 0x0802_0000,
    accepted: 0x0802_0000..0x0808_0000 - 100,
    behind_bootloader: true,
    reserved_flash: &[
        (
            0x0800_0000..0x0800_8000,
            "Tau Labs bootloader (sectors 0-1)",
        ),
        F405_SETTINGS,
    ],
    ram: F405_RAM,
    sp_mask: Some((0x2FFE_0000, 0x2000_0000)),
    uf2_family: None,
};

/// Module image at 0x0 for a debug probe (no MBR, no bootloader).
pub const NRF_PROBE: Layout = Layout {
    starter: "reset (debug probe)",
    origin: 0x0,
    accepted: 0x0..0xEA000,
    behind_bootloader: false,
    reserved_flash: &[NRF_SETTINGS],
    ram: 0x2000_0000..0x2004_0000,
    sp_mask: None,
    uf2_family: None,
};

/// Module image behind the Adafruit nRF52 bootloader with S140 v6 (nice!nano): UF2 blocks
/// only from 0x26000 (end of MBR + SoftDevice) to 0xEA000 (10 pages of application data
/// below the bootloader at 0xF4000); the MBR's forward words own RAM 0x2000_0000..08.
pub const NRF_UF2: Layout = Layout {
    starter: "Nordic MBR + Adafruit UF2 bootloader (S140 6.x)",
    origin: 0x26000,
    accepted: 0x26000..0xEA000,
    behind_bootloader: true,
    reserved_flash: &[
        (0x0..0x26000, "MBR and SoftDevice S140 6.x"),
        NRF_SETTINGS,
        (
            0xF4000..0x10_0000,
            "UF2 bootloader, MBR parameters, bootloader settings",
        ),
    ],
    ram: 0x2000_0008..0x2004_0000,
    sp_mask: None,
    uf2_family: Some(crate::formats::UF2_FAMILY_NRF52840),
};
