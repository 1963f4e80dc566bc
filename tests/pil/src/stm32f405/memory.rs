//! The memories: main flash (erased to 0xFF, programmed only through the flash interface
//! once an image is loaded), SRAM1+2, CCM data RAM, backup SRAM, the OTP block and the
//! factory words (unique ID, flash size, option bytes). Little-endian byte arrays; the SoC
//! decides who may reach which (CCM: data bus only).

use std::fmt;

use sim_rng::SplitMix64;

use super::map::{
    BKPSRAM_SIZE, CCM_SIZE, FLASH_BASE, FLASH_SIZE, OPTION_BYTES_SIZE, OTP_SIZE, SRAM_SIZE,
};

/// The flash size in KiB as the F405RG reports it at `FLASH_SIZE_REG`.
const FLASH_SIZE_KIB: u16 = 1024;
/// Option bytes at delivery (RM0090 §3.7.1): RDP level 0 (0xAA), USER 0xED (software
/// watchdog, no reset on stop/standby, BOR off), no write protection.
const OPTION_BYTES: [u8; OPTION_BYTES_SIZE as usize] = [
    0xED, 0xAA, 0x12, 0x55, 0, 0, 0, 0, 0xFF, 0x0F, 0x00, 0xF0, 0, 0, 0, 0,
];

/// Why an image cannot be loaded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LoadError {
    /// The ELF file could not be read.
    Elf(String),
    /// A loadable segment lies outside the main flash.
    OutsideFlash {
        /// The segment's load address.
        address: u32,
        /// Its length.
        len: usize,
    },
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoadError::Elf(e) => write!(f, "not a loadable image: {e}"),
            LoadError::OutsideFlash { address, len } => write!(
                f,
                "segment of {len} bytes at 0x{address:08x} is outside the 1 MiB flash at 0x{FLASH_BASE:08x}"
            ),
        }
    }
}

impl std::error::Error for LoadError {}

/// The chip's memories.
pub struct Memory {
    /// Main flash, 1 MiB.
    pub flash: Vec<u8>,
    /// SRAM1 + SRAM2, 128 KiB.
    pub sram: Vec<u8>,
    /// CCM data RAM, 64 KiB.
    pub ccm: Vec<u8>,
    /// Backup SRAM, 4 KiB.
    pub bkpsram: Vec<u8>,
    /// OTP data and lock bytes.
    pub otp: Vec<u8>,
    /// The factory block read at 0x1FFF_7A10: unique ID (12 bytes), then the flash size.
    pub factory: [u8; 20],
}

impl Memory {
    /// Erased flash and RAM with the contents `seed` draws (SRAM powers up with no defined
    /// contents; a seeded pattern keeps runs reproducible and never looks like zeroed RAM).
    pub fn new(seed: u64) -> Self {
        let mut m = Self {
            flash: vec![0xFF; FLASH_SIZE as usize],
            sram: vec![0; SRAM_SIZE as usize],
            ccm: vec![0; CCM_SIZE as usize],
            bkpsram: vec![0; BKPSRAM_SIZE as usize],
            otp: vec![0xFF; OTP_SIZE as usize],
            factory: [0; 20],
        };
        let mut rng = SplitMix64::new(seed ^ 0x5EED_F405);
        for b in m.factory.iter_mut().take(12) {
            *b = rng.byte();
        }
        let [lo, hi] = FLASH_SIZE_KIB.to_le_bytes();
        if let Some(s) = m.factory.get_mut(18..20) {
            s.copy_from_slice(&[lo, hi]);
        }
        m.power_on(seed);
        m
    }

    /// What power loss does to volatile memory: SRAM, CCM and backup SRAM (no VBAT on
    /// these boards) come back with arbitrary contents.
    pub fn power_on(&mut self, seed: u64) {
        let mut rng = SplitMix64::new(seed);
        for ram in [&mut self.sram, &mut self.ccm, &mut self.bkpsram] {
            for chunk in ram.chunks_mut(8) {
                let word = rng.next_u64().to_le_bytes();
                chunk.copy_from_slice(word.get(..chunk.len()).unwrap_or_default());
            }
        }
    }

    /// Copies an ELF file's loadable segments (by load address) into the main flash, as a
    /// programmer would; everything else stays erased.
    pub fn load_elf(&mut self, elf: &[u8]) -> Result<(), LoadError> {
        let segments = fw_elf::load_segments(elf).map_err(|e| LoadError::Elf(e.to_string()))?;
        for s in &segments {
            self.program(s.address, &s.data)?;
        }
        Ok(())
    }

    /// Puts `data` at flash address `address` (0x0800_0000-based).
    pub fn program(&mut self, address: u32, data: &[u8]) -> Result<(), LoadError> {
        let outside = LoadError::OutsideFlash {
            address,
            len: data.len(),
        };
        let start = address.checked_sub(FLASH_BASE).ok_or(outside.clone())? as usize;
        let dest = self
            .flash
            .get_mut(start..start + data.len())
            .ok_or(outside)?;
        dest.copy_from_slice(data);
        Ok(())
    }

    /// The option bytes.
    pub fn option_bytes() -> &'static [u8] {
        &OPTION_BYTES
    }
}

/// Little-endian load of `width` bytes (1, 2 or 4) at `offset`.
pub fn load(bytes: &[u8], offset: u32, width: u32) -> Option<u32> {
    let o = offset as usize;
    match width {
        4 => bytes
            .get(o..o + 4)
            .and_then(|s| s.try_into().ok())
            .map(u32::from_le_bytes),
        2 => bytes
            .get(o..o + 2)
            .and_then(|s| s.try_into().ok())
            .map(|b| u32::from(u16::from_le_bytes(b))),
        _ => bytes.get(o).map(|&b| u32::from(b)),
    }
}

/// Little-endian store of the low `width` bytes of `value` at `offset`.
pub fn store(bytes: &mut [u8], offset: u32, width: u32, value: u32) -> bool {
    let o = offset as usize;
    let le = value.to_le_bytes();
    match (
        bytes.get_mut(o..o + width as usize),
        le.get(..width as usize),
    ) {
        (Some(dest), Some(src)) => {
            dest.copy_from_slice(src);
            true
        }
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loads_and_stores_are_little_endian() {
        let mut b = [0u8; 8];
        assert!(store(&mut b, 1, 4, 0x1122_3344));
        assert_eq!(b, [0, 0x44, 0x33, 0x22, 0x11, 0, 0, 0]);
        assert_eq!(load(&b, 1, 4), Some(0x1122_3344));
        assert_eq!(load(&b, 2, 2), Some(0x2233));
        assert_eq!(load(&b, 6, 4), None);
        assert!(!store(&mut b, 7, 2, 0));
    }

    #[test]
    fn flash_starts_erased_and_only_takes_flash_addresses() {
        let mut m = Memory::new(1);
        assert!(m.flash.iter().all(|&b| b == 0xFF));
        assert!(m.program(0x0800_0100, &[1, 2, 3]).is_ok());
        assert_eq!(m.flash.get(0x100..0x103), Some(&[1u8, 2, 3][..]));
        assert_eq!(
            m.program(0x2000_0000, &[1]),
            Err(LoadError::OutsideFlash {
                address: 0x2000_0000,
                len: 1
            })
        );
        assert!(m.program(0x080F_FFFF, &[1, 2]).is_err());
        assert_eq!(load(&m.factory, 18, 2), Some(1024));
    }

    #[test]
    fn power_on_contents_depend_on_the_seed_only() {
        let (a, b, c) = (Memory::new(7), Memory::new(7), Memory::new(8));
        assert_eq!(a.sram, b.sram);
        assert_ne!(a.sram, c.sram);
        assert!(a.sram.iter().any(|&x| x != 0));
    }
}
