//! The data side of the core: alignment rules, the routing of an access to the core's own
//! registers, the bit-band aliases or the bus, bus faults and stalls, and what the core
//! re-reads from the bus after touching a peripheral.
//!
//! Accesses to the Code and SRAM regions of the ARMv7-M memory map (below 0x4000_0000) are
//! plain memory: the core does not re-sample interrupt lines, clock or next event after
//! them. After accesses at 0x4000_0000 and above (peripherals, devices, the vendor system
//! region) it does.

use crate::bus::{Bus, Width};
use crate::cpu::Cpu;
use crate::fault::Fault;

/// The first address of the peripheral region.
const PERIPHERAL: u32 = 0x4000_0000;
/// The SRAM and peripheral bit-band alias regions (32 MiB each) and what they alias.
const SRAM_ALIAS: u32 = 0x2200_0000;
const PERIPH_ALIAS: u32 = 0x4200_0000;
const ALIAS_SIZE: u32 = 0x0200_0000;

/// The execute-never regions of the default memory map (B3.1): peripherals, devices,
/// system.
pub(crate) fn never_executable(addr: u32) -> bool {
    (0x4000_0000..0x6000_0000).contains(&addr) || addr >= 0xA000_0000
}

impl Cpu {
    /// A load by an instruction: `aligned` for the accesses that must be aligned (LDM,
    /// LDRD, exclusives); others split when CCR.UNALIGN_TRP is clear.
    #[inline]
    pub(crate) fn load<B: Bus>(
        &mut self,
        bus: &mut B,
        addr: u32,
        width: Width,
        aligned: bool,
    ) -> Result<u32, Fault> {
        let misaligned = addr & (width.bytes() - 1) != 0;
        if !misaligned {
            return self.load_raw(bus, addr, width);
        }
        if aligned || self.scb.ccr & (1 << 3) != 0 {
            return Err(Fault::Unaligned);
        }
        let mut v = 0;
        for i in 0..width.bytes() {
            v |= self.load_raw(bus, addr.wrapping_add(i), Width::Byte)? << (8 * i);
        }
        self.clock.cycles += 1;
        Ok(v)
    }

    /// A store by an instruction (alignment as [`Cpu::load`]).
    #[inline]
    pub(crate) fn store<B: Bus>(
        &mut self,
        bus: &mut B,
        addr: u32,
        width: Width,
        value: u32,
        aligned: bool,
    ) -> Result<(), Fault> {
        let misaligned = addr & (width.bytes() - 1) != 0;
        if !misaligned {
            return self.store_raw(bus, addr, width, value);
        }
        if aligned || self.scb.ccr & (1 << 3) != 0 {
            return Err(Fault::Unaligned);
        }
        for i in 0..width.bytes() {
            self.store_raw(bus, addr.wrapping_add(i), Width::Byte, value >> (8 * i))?;
        }
        self.clock.cycles += 1;
        Ok(())
    }

    /// An aligned load, routed.
    #[inline(always)]
    pub(crate) fn load_raw<B: Bus>(
        &mut self,
        bus: &mut B,
        addr: u32,
        width: Width,
    ) -> Result<u32, Fault> {
        if addr < SRAM_ALIAS {
            let v = bus
                .read(addr, width, self.clock.now_ns())
                .map_err(|e| Fault::BusData(e.addr))?;
            self.clock.cycles += u64::from(bus.access_stall(addr, false));
            return Ok(v);
        }
        self.load_slow(bus, addr, width)
    }

    /// An aligned store, routed.
    #[inline(always)]
    pub(crate) fn store_raw<B: Bus>(
        &mut self,
        bus: &mut B,
        addr: u32,
        width: Width,
        value: u32,
    ) -> Result<(), Fault> {
        let value = match width {
            Width::Byte => value & 0xFF,
            Width::Half => value & 0xFFFF,
            Width::Word => value,
        };
        if addr < SRAM_ALIAS {
            self.cache.invalidate(addr, width.bytes());
            bus.write(addr, width, value, self.clock.now_ns())
                .map_err(|e| Fault::BusData(e.addr))?;
            self.clock.cycles += u64::from(bus.access_stall(addr, true));
            return Ok(());
        }
        self.store_slow(bus, addr, width, value)
    }

    /// The target word address and bit of a bit-band alias address, if `addr` is one.
    fn bitband(&self, addr: u32) -> Option<(u32, u32)> {
        if !self.cfg.bitband {
            return None;
        }
        let base = if (SRAM_ALIAS..SRAM_ALIAS + ALIAS_SIZE).contains(&addr) {
            SRAM_ALIAS
        } else if (PERIPH_ALIAS..PERIPH_ALIAS + ALIAS_SIZE).contains(&addr) {
            PERIPH_ALIAS
        } else {
            return None;
        };
        let off = addr - base;
        let region = base - 0x0200_0000;
        Some((region + (off >> 5), (off >> 2) & 7))
    }

    #[inline(never)]
    fn load_slow<B: Bus>(&mut self, bus: &mut B, addr: u32, width: Width) -> Result<u32, Fault> {
        if crate::scs::core_owned(addr) {
            let privileged = self.privileged();
            return self.scs_read(addr, width, privileged);
        }
        if let Some((byte_addr, bit)) = self.bitband(addr) {
            // The target is read with the alias access's size.
            let target = byte_addr & !(width.bytes() - 1);
            let bit = bit + 8 * (byte_addr - target);
            let v = self.load_raw(bus, target, width)?;
            return Ok(v >> bit & 1);
        }
        let v = bus
            .read(addr, width, self.clock.now_ns())
            .map_err(|e| Fault::BusData(e.addr))?;
        self.clock.cycles += u64::from(bus.access_stall(addr, false));
        if addr >= PERIPHERAL {
            self.after_peripheral_access(bus, false);
        }
        Ok(v)
    }

    #[inline(never)]
    fn store_slow<B: Bus>(
        &mut self,
        bus: &mut B,
        addr: u32,
        width: Width,
        value: u32,
    ) -> Result<(), Fault> {
        if crate::scs::core_owned(addr) {
            let privileged = self.privileged();
            return self.scs_write(addr, width, value, privileged);
        }
        if let Some((byte_addr, bit)) = self.bitband(addr) {
            let target = byte_addr & !(width.bytes() - 1);
            let bit = bit + 8 * (byte_addr - target);
            let old = self.load_raw(bus, target, width)?;
            let new = old & !(1 << bit) | (value & 1) << bit;
            return self.store_raw(bus, target, width, new);
        }
        if !never_executable(addr) {
            self.cache.invalidate(addr, width.bytes());
        }
        bus.write(addr, width, value, self.clock.now_ns())
            .map_err(|e| Fault::BusData(e.addr))?;
        self.clock.cycles += u64::from(bus.access_stall(addr, true));
        if addr >= PERIPHERAL {
            self.after_peripheral_access(bus, true);
        }
        Ok(())
    }
}
