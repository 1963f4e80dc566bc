//! The bus matrix: which memory or peripheral an address reaches (and through which bus,
//! for the stall), bit-band aliases, narrow accesses, clock gating, and the
//! not-modelled record.

use m4_sim::{BusFault, Width};

use super::map::{self, Block};
use super::memory;
use super::{Stm32f405, TIMER_KINDS};
use crate::wire::Outside;

/// Where a memory address lands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Region {
    Flash(u32),
    Sram(u32),
    Ccm(u32),
    Bkpsram(u32),
    Otp(u32),
    Factory(u32),
    OptionBytes(u32),
    SystemMemory(u32),
    SramBitBand(u32, u32),
    PeriphBitBand(u32, u32),
}

impl<O: Outside> Stm32f405<O> {
    fn region(&self, addr: u32) -> Option<Region> {
        let within = |base: u32, size: u32| addr.checked_sub(base).filter(|&o| o < size);
        if let Some(o) = within(map::SRAM_BASE, map::SRAM_SIZE) {
            return Some(Region::Sram(o));
        }
        if let Some(o) = within(map::FLASH_BASE, map::FLASH_SIZE) {
            return Some(Region::Flash(o));
        }
        if let Some(o) = within(map::CCM_BASE, map::CCM_SIZE) {
            return Some(Region::Ccm(o));
        }
        if addr < map::FLASH_SIZE {
            // The boot alias at 0 (SYSCFG_MEMRMP.MEM_MODE).
            return match self.exti.mem_mode() {
                0 => Some(Region::Flash(addr)),
                1 => within(0, map::SYSTEM_MEMORY_SIZE).map(Region::SystemMemory),
                3 => within(0, 112 * 1024).map(Region::Sram),
                _ => None,
            };
        }
        if let Some(o) = within(map::BKPSRAM_BASE, map::BKPSRAM_SIZE) {
            return Some(Region::Bkpsram(o));
        }
        if let Some(o) = within(map::OTP_BASE, map::OTP_SIZE) {
            return Some(Region::Otp(o));
        }
        if let Some(o) = within(map::UNIQUE_ID_BASE, 20) {
            return Some(Region::Factory(o));
        }
        if let Some(o) = within(map::OPTION_BYTES_BASE, map::OPTION_BYTES_SIZE) {
            return Some(Region::OptionBytes(o));
        }
        if let Some(o) = within(map::SYSTEM_MEMORY_BASE, map::SYSTEM_MEMORY_SIZE) {
            return Some(Region::SystemMemory(o));
        }
        // Bit-band: alias word (byte · 32 + bit · 4) → the bit of the byte's word.
        let bit_of = |o: u32| (o >> 5 & !3, (o >> 5 & 3) * 8 + (o >> 2 & 7));
        if let Some(o) = within(map::SRAM_BITBAND_BASE, map::BITBAND_ALIAS_SIZE) {
            let (word, bit) = bit_of(o);
            return Some(Region::SramBitBand(map::SRAM_BASE + word, bit));
        }
        if let Some(o) = within(map::PERIPH_BITBAND_BASE, map::BITBAND_ALIAS_SIZE) {
            let (word, bit) = bit_of(o);
            return Some(Region::PeriphBitBand(0x4000_0000 + word, bit));
        }
        None
    }

    /// An instruction halfword.
    pub(crate) fn fetch_halfword(&mut self, addr: u32) -> Option<u16> {
        let value = match self.region(addr)? {
            Region::Flash(o) => memory::load(&self.mem.flash, o, 2),
            Region::Sram(o) => {
                self.code_pages |= 1u128 << ((o >> 10) & 127);
                memory::load(&self.mem.sram, o, 2)
            }
            Region::Ccm(_) => {
                self.diag.violation(
                    "instruction fetch from CCM RAM (data bus only, RM0090 §2.3.1): fetch fault",
                    self.now,
                );
                None
            }
            Region::SystemMemory(_) => {
                self.diag.unmodelled(
                    addr,
                    false,
                    0,
                    "system memory (ST bootloader ROM)",
                    self.now,
                );
                None
            }
            _ => None,
        };
        value.map(|v| v as u16)
    }

    /// Brings the chip to `now` before an access.
    fn touch(&mut self, now: u64) {
        if now >= self.next_due {
            self.catch_up(now);
        }
        if now > self.now {
            self.now = now;
        }
    }

    /// A data load from the core.
    pub(crate) fn bus_read(&mut self, addr: u32, width: Width, now: u64) -> Result<u32, BusFault> {
        self.touch(now);
        let bytes = width.bytes();
        let fault = BusFault { addr, write: false };
        match self.region(addr) {
            Some(Region::Sram(o)) => memory::load(&self.mem.sram, o, bytes).ok_or(fault),
            Some(Region::Flash(o)) => {
                self.last_stall = self.flash.data_stall(o, now, self.clocks.hclk);
                memory::load(&self.mem.flash, o, bytes).ok_or(fault)
            }
            Some(Region::Ccm(o)) => memory::load(&self.mem.ccm, o, bytes).ok_or(fault),
            Some(Region::Bkpsram(o)) => {
                if !self.rcc.bkpsram_clocked() {
                    self.diag
                        .violation("backup SRAM read with AHB1ENR.BKPSRAMEN off", now);
                    return Ok(0);
                }
                memory::load(&self.mem.bkpsram, o, bytes).ok_or(fault)
            }
            Some(Region::Otp(o)) => memory::load(&self.mem.otp, o, bytes).ok_or(fault),
            Some(Region::Factory(o)) => memory::load(&self.mem.factory, o, bytes).ok_or(fault),
            Some(Region::OptionBytes(o)) => {
                memory::load(memory::Memory::option_bytes(), o, bytes).ok_or(fault)
            }
            Some(Region::SystemMemory(_)) => {
                self.diag
                    .unmodelled(addr, false, 0, "system memory (ST bootloader ROM)", now);
                Ok(0)
            }
            Some(Region::SramBitBand(word, bit)) => {
                Ok(memory::load(&self.mem.sram, word - map::SRAM_BASE, 4).ok_or(fault)? >> bit & 1)
            }
            Some(Region::PeriphBitBand(word, bit)) => {
                Ok(self.peripheral_read(word, Width::Word, now)? >> bit & 1)
            }
            None => self.peripheral_read(addr, width, now),
        }
    }

    /// A data store from the core.
    pub(crate) fn bus_write(
        &mut self,
        addr: u32,
        width: Width,
        value: u32,
        now: u64,
    ) -> Result<(), BusFault> {
        self.touch(now);
        let bytes = width.bytes();
        let fault = BusFault { addr, write: true };
        match self.region(addr) {
            Some(Region::Sram(o)) => {
                if self.code_pages != 0 && self.code_pages & (1u128 << ((o >> 10) & 127)) != 0 {
                    self.ram_code_generation += 1;
                }
                memory::store(&mut self.mem.sram, o, bytes, value)
                    .then_some(())
                    .ok_or(fault)
            }
            Some(Region::Ccm(o)) => memory::store(&mut self.mem.ccm, o, bytes, value)
                .then_some(())
                .ok_or(fault),
            Some(Region::Flash(o)) => {
                let fx = self
                    .flash
                    .program(&mut self.mem.flash, o, bytes, value, now);
                self.last_stall = ns_to_cycles(fx.stall_ns, self.clocks.hclk);
                if let Some(v) = fx.violation {
                    self.diag.violation(v, now);
                }
                self.refresh(now);
                Ok(())
            }
            Some(Region::Bkpsram(o)) => {
                if !self.rcc.bkpsram_clocked() || self.rcc.pwr_read(0).unwrap_or(0) & (1 << 8) == 0
                {
                    self.diag.violation(
                        "backup SRAM write without BKPSRAMEN and PWR_CR.DBP (RM0090 §5.1.2): ignored",
                        now,
                    );
                    return Ok(());
                }
                memory::store(&mut self.mem.bkpsram, o, bytes, value)
                    .then_some(())
                    .ok_or(fault)
            }
            Some(Region::Otp(_)) | Some(Region::OptionBytes(_)) => {
                self.diag
                    .unmodelled(addr, true, value, "OTP / option byte programming", now);
                Ok(())
            }
            Some(Region::Factory(_)) | Some(Region::SystemMemory(_)) => Err(fault),
            Some(Region::SramBitBand(word, bit)) => {
                let o = word - map::SRAM_BASE;
                let old = memory::load(&self.mem.sram, o, 4).ok_or(fault)?;
                let new = (old & !(1 << bit)) | ((value & 1) << bit);
                memory::store(&mut self.mem.sram, o, 4, new);
                Ok(())
            }
            Some(Region::PeriphBitBand(word, bit)) => {
                let old = self.peripheral_read(word, Width::Word, now)?;
                let new = (old & !(1 << bit)) | ((value & 1) << bit);
                self.peripheral_write(word, Width::Word, new, now, false)
            }
            None => self.peripheral_write(addr, width, value, now, false),
        }
    }

    /// A peripheral register load.
    pub(crate) fn peripheral_read(
        &mut self,
        addr: u32,
        width: Width,
        now: u64,
    ) -> Result<u32, BusFault> {
        let fault = BusFault { addr, write: false };
        let (block, offset) = map::decode(addr).ok_or(fault)?;
        if !addr.is_multiple_of(width.bytes()) {
            return Err(fault);
        }
        self.last_stall = self.rcc.access_cycles(block, now);
        if !self.rcc.clocked(block) {
            self.diag.violation(
                &format!("{block:?} read with its RCC clock off (reads 0, RM0090 §7.3)"),
                now,
            );
            return Ok(0);
        }
        let aligned = offset & !3;
        let Some(word) = self.block_read(block, aligned, now) else {
            let what = match block {
                Block::Unmodelled(name) => name.to_string(),
                b => format!("{b:?} register +0x{aligned:02x}"),
            };
            self.diag.unmodelled(addr, false, 0, &what, now);
            return Ok(0);
        };
        self.after_access(block, now);
        let shift = 8 * (offset & 3);
        let mask = match width {
            Width::Byte => 0xFF,
            Width::Half => 0xFFFF,
            Width::Word => u32::MAX,
        };
        Ok((word >> shift) & mask)
    }

    /// A peripheral register store (`dma`: the DMA controller writes).
    pub(crate) fn peripheral_write(
        &mut self,
        addr: u32,
        width: Width,
        value: u32,
        now: u64,
        dma: bool,
    ) -> Result<(), BusFault> {
        let fault = BusFault { addr, write: true };
        let (block, offset) = map::decode(addr).ok_or(fault)?;
        if !addr.is_multiple_of(width.bytes()) {
            return Err(fault);
        }
        self.last_stall = self.rcc.access_cycles(block, now);
        if !self.rcc.clocked(block) {
            self.diag.violation(
                &format!("{block:?} written with its RCC clock off (ignored, RM0090 §7.3)"),
                now,
            );
            return Ok(());
        }
        let aligned = offset & !3;
        let shift = 8 * (offset & 3);
        let lane_mask = match width {
            Width::Byte => 0xFFu32 << shift,
            Width::Half => 0xFFFFu32 << shift,
            Width::Word => u32::MAX,
        };
        let lanes = value << shift & lane_mask;
        let handled = match block {
            Block::Gpio(port) => {
                let changed =
                    self.gpio
                        .write(port, aligned, lanes, lane_mask, &mut self.outside, now);
                if let Some(pins) = &changed {
                    self.pins_changed(pins, now);
                }
                changed.is_some()
            }
            _ if shift != 0 => {
                self.diag
                    .unmodelled(addr, true, value, "narrow write to an upper byte lane", now);
                true
            }
            _ => self.block_write(block, aligned, lanes, now, dma),
        };
        if !handled {
            let what = match block {
                Block::Unmodelled(name) => name.to_string(),
                b => format!("{b:?} register +0x{aligned:02x}"),
            };
            self.diag.unmodelled(addr, true, value, &what, now);
        }
        if std::mem::take(&mut self.flash_bus_error) {
            return Err(fault);
        }
        self.after_access(block, now);
        Ok(())
    }

    fn block_read(&mut self, block: Block, offset: u32, now: u64) -> Option<u32> {
        match block {
            Block::Rcc => self.rcc.read(offset, now),
            Block::Pwr => self.rcc.pwr_read(offset),
            Block::FlashIf => self.flash.read(offset),
            Block::Gpio(port) => self.gpio.read(port, offset, &mut self.outside, now),
            Block::Syscfg => self.exti.syscfg_read(offset),
            Block::Exti => self.exti.read(offset),
            Block::Tim2 | Block::Tim3 | Block::Tim6 | Block::Tim9 => {
                self.timers.get(timer_index(block)?)?.read(offset, now)
            }
            Block::Dma(c) => self.dma.get(usize::from(c))?.read(offset),
            Block::Spi1 => self.spi[0].read(offset),
            Block::Spi3 => self.spi[1].read(offset),
            Block::I2c1 => {
                self.observe_i2c_lines(now);
                self.i2c.read(offset, now)
            }
            Block::Usart1 => self.usart.read(offset),
            Block::Adc1 => self.adc.read(offset),
            Block::AdcCommon => self.adc.common_read(offset),
            Block::Dac => self.dac.read(offset),
            Block::Iwdg => self.iwdg.read(offset, now),
            Block::Rng => {
                self.rng
                    .set_clocks(self.clocks.pll48, self.clocks.hclk, now);
                self.rng.read(offset, now)
            }
            Block::OtgFs => self.otg.read(offset, now),
            Block::Dbgmcu => match offset {
                // DEV_ID 0x413 (STM32F405/407/415/417), REV_ID 0x1007 (revision 2).
                0x00 => Some(0x1007_0413),
                0x04 | 0x08 | 0x0C => self.dbgmcu.get(((offset - 4) / 4) as usize).copied(),
                _ => None,
            },
            Block::Unmodelled(_) => None,
        }
    }

    fn block_write(&mut self, block: Block, offset: u32, value: u32, now: u64, dma: bool) -> bool {
        match block {
            Block::Rcc => self.rcc_write(offset, value, now),
            Block::Pwr => match self.rcc.pwr_write(offset, value) {
                Some(notes) => {
                    for n in notes {
                        self.diag
                            .unmodelled(0x4000_7000 + offset, true, value, n, now);
                    }
                    true
                }
                None => false,
            },
            Block::FlashIf => {
                let Some(fx) = self.flash.write(offset, value, &mut self.mem.flash, now) else {
                    return false;
                };
                self.last_stall = ns_to_cycles(fx.stall_ns, self.clocks.hclk);
                if let Some(v) = fx.violation {
                    self.diag.violation(v, now);
                }
                if let Some(u) = fx.unmodelled {
                    self.diag
                        .unmodelled(0x4002_3C00 + offset, true, value, u, now);
                }
                if fx.bus_error {
                    self.flash_bus_error = true;
                }
                if offset == 0 {
                    self.check_flash_latency(now);
                }
                true
            }
            Block::Syscfg => match self.exti.syscfg_write(offset, value) {
                Some(note) => {
                    if let Some(n) = note {
                        self.diag
                            .unmodelled(0x4001_3800 + offset, true, value, n, now);
                    }
                    self.resync_exti_lines(now);
                    true
                }
                None => false,
            },
            Block::Exti => match self.exti.write(offset, value) {
                Some(note) => {
                    if let Some(n) = note {
                        self.diag
                            .unmodelled(0x4001_3C00 + offset, true, value, n, now);
                    }
                    true
                }
                None => false,
            },
            Block::Tim2 | Block::Tim3 | Block::Tim6 | Block::Tim9 => {
                let Some(t) = timer_index(block).and_then(|i| self.timers.get_mut(i)) else {
                    return false;
                };
                t.write(offset, value, now).is_some()
            }
            Block::Dma(c) => self
                .dma
                .get_mut(usize::from(c))
                .and_then(|d| d.write(offset, value))
                .is_some(),
            Block::Spi1 => self.spi[0].write(offset, value, now).is_some(),
            Block::Spi3 => self.spi[1].write(offset, value, now).is_some(),
            Block::I2c1 => {
                self.observe_i2c_lines(now);
                self.i2c.write(offset, value, now).is_some()
            }
            Block::Usart1 => self.usart.write(offset, value, now).is_some(),
            Block::Adc1 => self.adc.write(offset, value, now).is_some(),
            Block::AdcCommon => self.adc.common_write(offset, value).is_some(),
            Block::Dac => self.dac.write(offset, value, now, dma).is_some(),
            Block::Iwdg => match self.iwdg.write(offset, value, now) {
                Some(started) => {
                    if started {
                        self.rcc.force_lsi(now);
                    }
                    true
                }
                None => false,
            },
            Block::Rng => {
                self.rng
                    .set_clocks(self.clocks.pll48, self.clocks.hclk, now);
                self.rng.write(offset, value, now).is_some()
            }
            Block::OtgFs => self.otg.write(offset, value, now).is_some(),
            Block::Dbgmcu => match offset {
                0x04 | 0x08 | 0x0C => {
                    if let Some(r) = self.dbgmcu.get_mut(((offset - 4) / 4) as usize) {
                        *r = value;
                    }
                    true
                }
                _ => false,
            },
            // GPIO writes go through `Gpio::write` with their byte lanes.
            Block::Gpio(_) | Block::Unmodelled(_) => false,
        }
    }

    fn rcc_write(&mut self, offset: u32, value: u32, now: u64) -> bool {
        let Some(fx) = self.rcc.write(offset, value, now) else {
            return false;
        };
        for v in &fx.violations {
            self.diag.violation(v, now);
        }
        for u in &fx.unmodelled {
            self.diag
                .unmodelled(0x4002_3800 + offset, true, value, u, now);
        }
        for b in &fx.reset {
            self.reset_block(*b, now);
        }
        // Enables change clocks as much as the tree does.
        self.on_clock_change(now);
        true
    }
}

/// The index in `timers` of a timer block.
pub(crate) fn timer_index(block: Block) -> Option<usize> {
    let n = match block {
        Block::Tim2 => 2,
        Block::Tim3 => 3,
        Block::Tim6 => 6,
        Block::Tim9 => 9,
        _ => return None,
    };
    TIMER_KINDS.iter().position(|k| k.number == n)
}

/// Nanoseconds to core cycles at `hz`, saturating.
pub(crate) fn ns_to_cycles(ns: u64, hz: u32) -> u32 {
    u32::try_from(u128::from(ns) * u128::from(hz) / 1_000_000_000).unwrap_or(u32::MAX)
}
