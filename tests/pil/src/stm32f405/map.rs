//! The STM32F405's address map and interrupt numbers, declared once: memories and
//! peripheral base addresses from RM0090 §2.3 "Memory map" (Table 1), IRQ numbers from
//! RM0090 Table 61 "Vector table for STM32F405xx/07xx and STM32F415xx/17xx".

/// Main flash: 1 MiB (STM32F405RG), sectors 0–11.
pub const FLASH_BASE: u32 = 0x0800_0000;
/// Size of the main flash.
pub const FLASH_SIZE: u32 = 1024 * 1024;
/// SRAM1 (112 KiB) and SRAM2 (16 KiB), contiguous.
pub const SRAM_BASE: u32 = 0x2000_0000;
/// Size of SRAM1 + SRAM2.
pub const SRAM_SIZE: u32 = 128 * 1024;
/// Core-coupled data RAM: D-bus only (no instruction fetch, no DMA).
pub const CCM_BASE: u32 = 0x1000_0000;
/// Size of the CCM data RAM.
pub const CCM_SIZE: u32 = 64 * 1024;
/// Backup SRAM on AHB1 (kept by the backup regulator; here: kept across resets).
pub const BKPSRAM_BASE: u32 = 0x4002_4000;
/// Size of the backup SRAM.
pub const BKPSRAM_SIZE: u32 = 4 * 1024;
/// System memory (ST's ROM bootloader): not modelled, reads are recorded.
pub const SYSTEM_MEMORY_BASE: u32 = 0x1FFF_0000;
/// Size of the system memory.
pub const SYSTEM_MEMORY_SIZE: u32 = 30 * 1024;
/// One-time-programmable area (512 bytes) and its 16 lock bytes.
pub const OTP_BASE: u32 = 0x1FFF_7800;
/// Size of the OTP area with its lock block.
pub const OTP_SIZE: u32 = 528;
/// The 96-bit unique device ID (RM0090 §39.1).
pub const UNIQUE_ID_BASE: u32 = 0x1FFF_7A10;
/// The flash size register, in KiB (RM0090 §39.2).
pub const FLASH_SIZE_REG: u32 = 0x1FFF_7A22;
/// Option bytes (RDP/USER, nWRP).
pub const OPTION_BYTES_BASE: u32 = 0x1FFF_C000;
/// Size of the option bytes block.
pub const OPTION_BYTES_SIZE: u32 = 16;
/// SRAM bit-band alias region (maps 0x2000_0000–0x200F_FFFF one bit per word).
pub const SRAM_BITBAND_BASE: u32 = 0x2200_0000;
/// Peripheral bit-band alias region (maps 0x4000_0000–0x400F_FFFF).
pub const PERIPH_BITBAND_BASE: u32 = 0x4200_0000;
/// Size of each bit-band alias region.
pub const BITBAND_ALIAS_SIZE: u32 = 0x0200_0000;

/// A peripheral this crate models, or one it knows by name but does not model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Block {
    /// TIM2 (embassy's time driver).
    Tim2,
    /// TIM3 (motor outputs 1–2).
    Tim3,
    /// TIM6 (the DAC's pacer).
    Tim6,
    /// TIM9 (motor outputs 3–4).
    Tim9,
    /// Independent watchdog.
    Iwdg,
    /// SPI1 (MPU9250).
    Spi1,
    /// SPI3 (RFM22B, M25P16).
    Spi3,
    /// I2C1 (MS5611).
    I2c1,
    /// Power controller.
    Pwr,
    /// DAC (channel 1 on PA4).
    Dac,
    /// USART1 (Sparky2 GPS).
    Usart1,
    /// ADC1.
    Adc1,
    /// The ADC common registers (CSR, CCR, CDR).
    AdcCommon,
    /// System configuration controller (EXTICR, MEMRMP).
    Syscfg,
    /// External interrupt controller.
    Exti,
    /// GPIO port A (0) … I (8).
    Gpio(u8),
    /// Reset and clock control.
    Rcc,
    /// The flash interface registers.
    FlashIf,
    /// DMA1 (0) or DMA2 (1).
    Dma(u8),
    /// USB OTG FS core.
    OtgFs,
    /// True random number generator.
    Rng,
    /// Debug MCU registers (IDCODE, freeze bits).
    Dbgmcu,
    /// A peripheral the chip has but this model does not.
    Unmodelled(&'static str),
}

/// Base address, size and block of every peripheral on the F405's buses.
const PERIPHERALS: [(u32, u32, Block); 60] = [
    (0x4000_0000, 0x400, Block::Tim2),
    (0x4000_0400, 0x400, Block::Tim3),
    (0x4000_0800, 0x400, Block::Unmodelled("TIM4")),
    (0x4000_0C00, 0x400, Block::Unmodelled("TIM5")),
    (0x4000_1000, 0x400, Block::Tim6),
    (0x4000_1400, 0x400, Block::Unmodelled("TIM7")),
    (0x4000_1800, 0x400, Block::Unmodelled("TIM12")),
    (0x4000_1C00, 0x400, Block::Unmodelled("TIM13")),
    (0x4000_2000, 0x400, Block::Unmodelled("TIM14")),
    (0x4000_2800, 0x400, Block::Unmodelled("RTC/BKP")),
    (0x4000_2C00, 0x400, Block::Unmodelled("WWDG")),
    (0x4000_3000, 0x400, Block::Iwdg),
    (0x4000_3400, 0x400, Block::Unmodelled("I2S2ext")),
    (0x4000_3800, 0x400, Block::Unmodelled("SPI2")),
    (0x4000_3C00, 0x400, Block::Spi3),
    (0x4000_4000, 0x400, Block::Unmodelled("I2S3ext")),
    (0x4000_4400, 0x400, Block::Unmodelled("USART2")),
    (0x4000_4800, 0x400, Block::Unmodelled("USART3")),
    (0x4000_4C00, 0x400, Block::Unmodelled("UART4")),
    (0x4000_5000, 0x400, Block::Unmodelled("UART5")),
    (0x4000_5400, 0x400, Block::I2c1),
    (0x4000_5800, 0x400, Block::Unmodelled("I2C2")),
    (0x4000_5C00, 0x400, Block::Unmodelled("I2C3")),
    (0x4000_6400, 0x400, Block::Unmodelled("CAN1")),
    (0x4000_6800, 0x400, Block::Unmodelled("CAN2")),
    (0x4000_7000, 0x400, Block::Pwr),
    (0x4000_7400, 0x400, Block::Dac),
    (0x4001_0000, 0x400, Block::Unmodelled("TIM1")),
    (0x4001_0400, 0x400, Block::Unmodelled("TIM8")),
    (0x4001_1000, 0x400, Block::Usart1),
    (0x4001_1400, 0x400, Block::Unmodelled("USART6")),
    (0x4001_2000, 0x100, Block::Adc1),
    (0x4001_2100, 0x100, Block::Unmodelled("ADC2")),
    (0x4001_2200, 0x100, Block::Unmodelled("ADC3")),
    (0x4001_2300, 0x100, Block::AdcCommon),
    (0x4001_2C00, 0x400, Block::Unmodelled("SDIO")),
    (0x4001_3000, 0x400, Block::Spi1),
    (0x4001_3800, 0x400, Block::Syscfg),
    (0x4001_3C00, 0x400, Block::Exti),
    (0x4001_4000, 0x400, Block::Tim9),
    (0x4001_4400, 0x400, Block::Unmodelled("TIM10")),
    (0x4001_4800, 0x400, Block::Unmodelled("TIM11")),
    (0x4002_0000, 0x400, Block::Gpio(0)),
    (0x4002_0400, 0x400, Block::Gpio(1)),
    (0x4002_0800, 0x400, Block::Gpio(2)),
    (0x4002_0C00, 0x400, Block::Gpio(3)),
    (0x4002_1000, 0x400, Block::Gpio(4)),
    (0x4002_1400, 0x400, Block::Gpio(5)),
    (0x4002_1800, 0x400, Block::Gpio(6)),
    (0x4002_1C00, 0x400, Block::Gpio(7)),
    (0x4002_2000, 0x400, Block::Gpio(8)),
    (0x4002_3000, 0x400, Block::Unmodelled("CRC")),
    (0x4002_3800, 0x400, Block::Rcc),
    (0x4002_3C00, 0x400, Block::FlashIf),
    (0x4002_6000, 0x400, Block::Dma(0)),
    (0x4002_6400, 0x400, Block::Dma(1)),
    (0x4002_8000, 0x1400, Block::Unmodelled("ETH")),
    (0x4004_0000, 0x4_0000, Block::Unmodelled("USB OTG HS")),
    (0x5000_0000, 0x4_0000, Block::OtgFs),
    (0x5006_0800, 0x400, Block::Rng),
];

/// The base address of `block` (for diagnostics).
pub fn base_of(block: Block) -> u32 {
    if block == Block::Dbgmcu {
        return DBGMCU_BASE;
    }
    PERIPHERALS
        .iter()
        .find(|(_, _, b)| *b == block)
        .map_or(0, |&(base, _, _)| base)
}

/// The DBGMCU block, outside the core's private peripheral bus.
pub const DBGMCU_BASE: u32 = 0xE004_2000;

/// The block at `addr` and the offset into it; `None` where nothing answers on the bus.
pub fn decode(addr: u32) -> Option<(Block, u32)> {
    if (DBGMCU_BASE..DBGMCU_BASE + 0x10).contains(&addr) {
        return Some((Block::Dbgmcu, addr - DBGMCU_BASE));
    }
    // The table is sorted by base address: the candidate is the last base at or below.
    let i = PERIPHERALS.partition_point(|&(base, _, _)| base <= addr);
    let &(base, size, block) = PERIPHERALS.get(i.checked_sub(1)?)?;
    (addr - base < size).then_some((block, addr - base))
}

/// Interrupt numbers (RM0090 Table 61).
pub mod irq {
    /// EXTI line 0.
    pub const EXTI0: u32 = 6;
    /// EXTI line 1.
    pub const EXTI1: u32 = 7;
    /// EXTI line 2.
    pub const EXTI2: u32 = 8;
    /// EXTI line 3.
    pub const EXTI3: u32 = 9;
    /// EXTI line 4.
    pub const EXTI4: u32 = 10;
    /// DMA1 streams 0–6 are 11–17; stream 7 is [`DMA1_STREAM7`].
    pub const DMA1_STREAM0: u32 = 11;
    /// ADC1–3.
    pub const ADC: u32 = 18;
    /// EXTI lines 5–9.
    pub const EXTI9_5: u32 = 23;
    /// TIM1 break and TIM9.
    pub const TIM1_BRK_TIM9: u32 = 24;
    /// TIM2.
    pub const TIM2: u32 = 28;
    /// TIM3.
    pub const TIM3: u32 = 29;
    /// I2C1 events.
    pub const I2C1_EV: u32 = 31;
    /// I2C1 errors.
    pub const I2C1_ER: u32 = 32;
    /// SPI1.
    pub const SPI1: u32 = 35;
    /// USART1.
    pub const USART1: u32 = 37;
    /// EXTI lines 10–15.
    pub const EXTI15_10: u32 = 40;
    /// DMA1 stream 7.
    pub const DMA1_STREAM7: u32 = 47;
    /// SPI3.
    pub const SPI3: u32 = 51;
    /// TIM6 and the DAC underrun.
    pub const TIM6_DAC: u32 = 54;
    /// DMA2 streams 0–4 are 56–60; streams 5–7 start at [`DMA2_STREAM5`].
    pub const DMA2_STREAM0: u32 = 56;
    /// DMA2 stream 5 (6 and 7 follow).
    pub const DMA2_STREAM5: u32 = 68;
    /// USB OTG FS.
    pub const OTG_FS: u32 = 67;
    /// Flash interface (end of operation, errors).
    pub const FLASH: u32 = 4;
    /// The hash processor and the RNG.
    pub const HASH_RNG: u32 = 80;

    /// The IRQ number of DMA `controller` (0 = DMA1) stream `stream`.
    pub fn dma_stream(controller: u8, stream: u8) -> u32 {
        let s = u32::from(stream);
        match (controller, stream) {
            (0, 0..=6) => DMA1_STREAM0 + s,
            (0, _) => DMA1_STREAM7,
            (_, 0..=4) => DMA2_STREAM0 + s,
            (_, _) => DMA2_STREAM5 + s - 5,
        }
    }

    /// The IRQ number serving EXTI `line` (0–15).
    pub fn exti(line: u8) -> u32 {
        match line {
            0 => EXTI0,
            1 => EXTI1,
            2 => EXTI2,
            3 => EXTI3,
            4 => EXTI4,
            5..=9 => EXTI9_5,
            _ => EXTI15_10,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_the_blocks_the_images_use_at_their_rm0090_addresses() {
        assert_eq!(decode(0x4002_3808), Some((Block::Rcc, 8)));
        assert_eq!(decode(0x4001_3C14), Some((Block::Exti, 0x14)));
        assert_eq!(decode(0x4002_0C10), Some((Block::Gpio(3), 0x10)));
        assert_eq!(decode(0x4002_64A0), Some((Block::Dma(1), 0xA0)));
        assert_eq!(decode(0x5000_0800), Some((Block::OtgFs, 0x800)));
        assert_eq!(decode(0xE004_2000), Some((Block::Dbgmcu, 0)));
        assert_eq!(decode(0x4000_0800), Some((Block::Unmodelled("TIM4"), 0)));
        assert_eq!(decode(0x4000_2400), None, "a reserved hole in APB1");
    }

    #[test]
    fn the_peripheral_table_is_sorted_and_disjoint() {
        for pair in PERIPHERALS.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            assert!(a.0 + a.1 <= b.0, "{:x} overlaps {:x}", a.0, b.0);
        }
    }

    #[test]
    fn dma_and_exti_irq_numbers_follow_the_vector_table() {
        assert_eq!(irq::dma_stream(0, 0), 11);
        assert_eq!(irq::dma_stream(0, 6), 17);
        assert_eq!(irq::dma_stream(0, 7), 47);
        assert_eq!(irq::dma_stream(1, 0), 56);
        assert_eq!(irq::dma_stream(1, 4), 60);
        assert_eq!(irq::dma_stream(1, 5), 68);
        assert_eq!(irq::dma_stream(1, 7), 70);
        assert_eq!(irq::exti(2), 8);
        assert_eq!(irq::exti(5), 23);
        assert_eq!(irq::exti(7), 23);
        assert_eq!(irq::exti(12), 40);
    }
}
