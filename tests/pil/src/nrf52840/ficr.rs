//! The factory information page (FICR, PS "FICR"): what the image may read about the chip.

use super::map::{FLASH_PAGE, FLASH_SIZE, RAM_SIZE};

/// The silicon build code in INFO.VARIANT (PS "FICR": INFO.VARIANT; build codes per
/// the nRF52840 compatibility matrix). embassy-nrf writes UICR.APPROTECT on build code F
/// and later (the "hardware and software controlled" access port protection).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Variant {
    /// AAD0: revision 1 build code D0.
    Aad0,
    /// AAF0: revision 3 build code F0 (current production).
    #[default]
    Aaf0,
}

impl Variant {
    /// INFO.VARIANT: four ASCII characters, most significant first.
    pub const fn code(self) -> u32 {
        match self {
            Variant::Aad0 => u32::from_be_bytes(*b"AAD0"),
            Variant::Aaf0 => u32::from_be_bytes(*b"AAF0"),
        }
    }
}

/// INFO.PART for the nRF52840.
const PART: u32 = 0x0005_2840;
/// INFO.PACKAGE: QIxx, aQFN73 (the package on nice!nano-class boards).
const PACKAGE_QI: u32 = 0x2004;

/// FICR.TEMP calibration words A0–A5, B0–B5, T0–T4 in register order: the TEMP peripheral's
/// reset values in the PS ("TEMP" register table), which is what a chip's factory page holds
/// on average. embassy-nrf copies them into TEMP (anomaly 66 workaround).
const TEMP_TRIM: [u32; 17] = [
    0x326, 0x348, 0x3AA, 0x40E, 0x4BD, 0x5A3, 0x3FEF, 0x3FBE, 0x3FBE, 0x12, 0x124, 0x27C, 0xE2,
    0x00, 0x19, 0x3C, 0x50,
];
/// Offset of FICR.TEMP.A0.
const TEMP_OFFSET: u32 = 0x404;

/// The FICR contents the model provides.
#[derive(Clone, Debug)]
pub struct Ficr {
    variant: Variant,
    device_id: u64,
}

impl Ficr {
    /// A chip with this build code and 64-bit device ID.
    pub const fn new(variant: Variant, device_id: u64) -> Self {
        Self { variant, device_id }
    }

    /// The word at `offset`; `None` where the model has no content.
    pub fn read(&self, offset: u32) -> Option<u32> {
        let id = self.device_id;
        Some(match offset {
            0x010 => FLASH_PAGE,
            0x014 => FLASH_SIZE / FLASH_PAGE,
            0x060 => id as u32,
            0x064 => (id >> 32) as u32,
            // DEVICEADDRTYPE random static, DEVICEADDR from the ID (BLE is unused).
            0x0A0 => 1,
            0x0A4 => (id >> 16) as u32,
            0x0A8 => (id >> 48) as u32 | 0xC000,
            0x100 => PART,
            0x104 => self.variant.code(),
            0x108 => PACKAGE_QI,
            0x10C => RAM_SIZE / 1024,
            0x110 => FLASH_SIZE / 1024,
            o if o >= TEMP_OFFSET && o % 4 == 0 => {
                *TEMP_TRIM.get(((o - TEMP_OFFSET) / 4) as usize)?
            }
            _ => return None,
        })
    }
}
