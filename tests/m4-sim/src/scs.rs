//! The memory-mapped registers the core owns: the System Control Space at 0xE000_E000
//! (NVIC, SCB, SysTick, MPU, FPU control, debug control) and the debug blocks ITM, DWT,
//! FPB (0xE000_0000–0xE000_2FFF) and TPIU (0xE004_0000). Values and bit layouts are the
//! ARM ARM's (B3.2–B3.5, C1) and the Cortex-M4 TRM's (ID registers).
//!
//! The MPU's registers are kept but regions are not enforced. ITM, FPB and TPIU read as
//! zero and ignore writes; with no debugger attached DHCSR reads zero (C_DEBUGEN = 0).

use crate::bus::Width;
use crate::cpu::Cpu;
use crate::exception::control;
use crate::fault::{Fault, shcsr};
use crate::nvic::exc;
use crate::systick;

/// CPUID: Arm, variant 0, Cortex-M4 (0xC24), revision 1 (r0p1).
const CPUID: u32 = 0x410F_C241;
/// ID_PFR0 … ID_ISAR4 at 0xE000_ED40 (Cortex-M4 TRM table 4-2).
const ID_REGS: [u32; 13] = [
    0x0000_0030,
    0x0000_0200,
    0x0010_0000,
    0x0000_0000,
    0x0010_0030,
    0x0000_0000,
    0x0100_0000,
    0x0000_0000,
    0x0110_1110,
    0x0211_1000,
    0x2111_2231,
    0x0111_1110,
    0x0131_0132,
];
/// MVFR0/MVFR1 of FPv4-SP.
const MVFR0: u32 = 0x1011_0021;
const MVFR1: u32 = 0x1100_0011;
/// CCR bits the M4 implements; STKALIGN resets to 1.
const CCR_MASK: u32 = 0x0000_031B;
const CCR_RESET: u32 = 1 << 9;

/// SCB state (everything but the priorities and exception bits, which live in the NVIC).
#[derive(Clone, Debug)]
pub(crate) struct Scb {
    pub actlr: u32,
    pub vtor: u32,
    pub prigroup: u8,
    pub scr: u32,
    pub ccr: u32,
    pub cfsr: u32,
    pub hfsr: u32,
    pub dfsr: u32,
    pub mmfar: u32,
    pub bfar: u32,
    pub afsr: u32,
    pub cpacr: u32,
    pub fpccr: u32,
    pub fpcar: u32,
    pub fpdscr: u32,
}

impl Scb {
    pub fn new() -> Self {
        Scb {
            actlr: 0,
            vtor: 0,
            prigroup: 0,
            scr: 0,
            ccr: CCR_RESET,
            cfsr: 0,
            hfsr: 0,
            dfsr: 0,
            mmfar: 0,
            bfar: 0,
            afsr: 0,
            cpacr: 0,
            fpccr: crate::exception::fpccr::ASPEN | crate::exception::fpccr::LSPEN,
            fpcar: 0,
            fpdscr: 0,
        }
    }
}

/// The MPU's registers (8 regions), kept and not enforced.
#[derive(Clone, Debug, Default)]
pub(crate) struct Mpu {
    pub ctrl: u32,
    pub rnr: u32,
    pub rbar: [u32; 8],
    pub rasr: [u32; 8],
}

/// Debug state that survives a core reset: DEMCR and DWT's cycle counter.
#[derive(Clone, Debug, Default)]
pub(crate) struct Debug {
    pub demcr: u32,
    pub dwt_ctrl: u32,
    /// CYCCNT at `active_at_base` active cycles.
    pub cyccnt_base: u32,
    pub active_at_base: u64,
}

impl Debug {
    /// A core reset leaves the debug registers alone (they reset with power only).
    pub fn reset_core(&mut self) {}
}

/// Whether the core (not the bus) answers at `addr`.
pub(crate) fn core_owned(addr: u32) -> bool {
    (0xE000_0000..0xE004_0000).contains(&addr) || (0xE004_0000..0xE004_1000).contains(&addr)
}

/// Registers written as a whole word even by a byte or halfword store (the write-one
/// actions and write-one-to-clear status): the other lanes write zero.
fn lanes_write_zero(off: u32) -> bool {
    matches!(off, 0x100..=0x2FF | 0xD04 | 0xD28..=0xD33 | 0xF00)
}

impl Cpu {
    /// Active processor cycles (CYCCNT's clock).
    fn active_cycles(&self) -> u64 {
        self.clock.cycles - self.stats.cycles_asleep
    }

    /// A load from a core-owned address.
    pub(crate) fn scs_read(
        &mut self,
        addr: u32,
        width: Width,
        privileged: bool,
    ) -> Result<u32, Fault> {
        if !privileged {
            return Err(Fault::BusData(addr));
        }
        let word = self.scs_read_word(addr & !3);
        let shift = 8 * (addr & 3);
        Ok(match width {
            Width::Word => word,
            Width::Half => word >> shift & 0xFFFF,
            Width::Byte => word >> shift & 0xFF,
        })
    }

    /// A store to a core-owned address.
    pub(crate) fn scs_write(
        &mut self,
        addr: u32,
        width: Width,
        value: u32,
        privileged: bool,
    ) -> Result<(), Fault> {
        let in_scs = addr >> 12 == 0xE000E;
        let off = addr & 0xFFF & !3;
        let stir_allowed = in_scs && off == 0xF00 && self.scb.ccr & 2 != 0;
        if !privileged && !stir_allowed {
            return Err(Fault::BusData(addr));
        }
        let shift = 8 * (addr & 3);
        let lane = match width {
            Width::Word => 0xFFFF_FFFF,
            Width::Half => 0xFFFF << shift,
            Width::Byte => 0xFF << shift,
        };
        let v = value << shift & lane;
        if in_scs && ((0x400..0x4F0).contains(&off) || (0xD18..0xD24).contains(&off)) {
            // Priority bytes: only the written lanes change.
            for i in 0..4 {
                if lane >> (8 * i) & 0xFF != 0 {
                    self.write_priority_byte(addr & !3 | i, (v >> (8 * i)) as u8);
                }
            }
        } else if width == Width::Word || !in_scs || lanes_write_zero(off) {
            self.scs_write_word(addr & !3, v);
        } else {
            let merged = self.scs_read_word(addr & !3) & !lane | v;
            self.scs_write_word(addr & !3, merged);
        }
        self.stop_at = 0;
        Ok(())
    }

    fn write_priority_byte(&mut self, addr: u32, v: u8) {
        let off = addr & 0xFFF;
        let n = if (0x400..0x4F0).contains(&off) {
            (off - 0x400) as u16 + exc::IRQ0
        } else {
            (off - 0xD14) as u16
        };
        let configurable = matches!(n, 4..=6 | 11 | 12 | 14 | 15)
            || (n >= exc::IRQ0 && self.nvic.irq_implemented(n - exc::IRQ0));
        if configurable {
            self.nvic.set_priority(n, v);
        }
    }

    fn read_priority_word(&self, base_exc: u16) -> u32 {
        (0..4u16).fold(0, |acc, i| {
            let n = base_exc + i;
            let p = if n >= 4 {
                self.nvic.priority(n).max(0) as u32
            } else {
                0
            };
            acc | (p & 0xFF) << (8 * i)
        })
    }

    fn scs_read_word(&mut self, addr: u32) -> u32 {
        match addr {
            0xE000_1000 => self.debug.dwt_ctrl | 4 << 28,
            0xE000_1004 => self.cyccnt(),
            0xE000_E000..=0xE000_EFFF => self.scb_read(addr & 0xFFF),
            _ => 0,
        }
    }

    fn cyccnt(&self) -> u32 {
        let base = self.debug.cyccnt_base;
        if self.debug.dwt_ctrl & 1 != 0 && self.debug.demcr & (1 << 24) != 0 {
            base.wrapping_add((self.active_cycles() - self.debug.active_at_base) as u32)
        } else {
            base
        }
    }

    /// Freezes CYCCNT's current value before its enables change.
    fn cyccnt_rebase(&mut self) {
        self.debug.cyccnt_base = self.cyccnt();
        self.debug.active_at_base = self.active_cycles();
    }

    fn scs_write_word(&mut self, addr: u32, v: u32) {
        match addr {
            0xE000_1000 => {
                self.cyccnt_rebase();
                self.debug.dwt_ctrl = v & 0x0FFF_FFFF;
            }
            0xE000_1004 => {
                self.debug.cyccnt_base = v;
                self.debug.active_at_base = self.active_cycles();
            }
            0xE000_E000..=0xE000_EFFF => self.scb_write(addr & 0xFFF, v),
            _ => {}
        }
    }

    fn icsr(&self) -> u32 {
        let ipsr = u32::from(self.ipsr);
        let active = self.nvic.active_count();
        let rettobase = active == 0 || (active == 1 && self.ipsr != 0);
        let vectpending = self.nvic.best_pending().map_or(0, |(n, _)| u32::from(n));
        u32::from(self.nvic.is_pending(exc::NMI)) << 31
            | u32::from(self.nvic.is_pending(exc::PENDSV)) << 28
            | u32::from(self.nvic.is_pending(exc::SYSTICK)) << 26
            | u32::from(self.nvic.any_irq_pending()) << 22
            | (vectpending & 0x1FF) << 12
            | u32::from(rettobase) << 11
            | ipsr & 0x1FF
    }

    fn shcsr(&self) -> u32 {
        let n = &self.nvic;
        let b = |x: bool, i: u32| u32::from(x) << i;
        b(n.is_active(exc::MEM_MANAGE), 0)
            | b(n.is_active(exc::BUS_FAULT), 1)
            | b(n.is_active(exc::USAGE_FAULT), 3)
            | b(n.is_active(exc::SVCALL), 7)
            | b(n.is_active(12), 8)
            | b(n.is_active(exc::PENDSV), 10)
            | b(n.is_active(exc::SYSTICK), 11)
            | b(n.is_pending(exc::USAGE_FAULT), 12)
            | b(n.is_pending(exc::MEM_MANAGE), 13)
            | b(n.is_pending(exc::BUS_FAULT), 14)
            | b(n.is_pending(exc::SVCALL), 15)
            | b(n.is_enabled(exc::MEM_MANAGE), 16)
            | b(n.is_enabled(exc::BUS_FAULT), 17)
            | b(n.is_enabled(exc::USAGE_FAULT), 18)
    }

    fn scb_read(&mut self, off: u32) -> u32 {
        let irq_reg = |base: u32| ((off - base) / 4) as usize;
        match off {
            0x004 => u32::from(self.nvic.irqs().div_ceil(32).saturating_sub(1)),
            0x008 => self.scb.actlr,
            0x010 => self.systick.read_csr(self.cfg.systick_ref_div),
            0x014 => self.systick.rvr,
            0x018 => self.systick.value(self.clock.cycles),
            0x01C => {
                let noref = u32::from(self.cfg.systick_ref_div.is_none()) << 31;
                let skew = u32::from(self.cfg.systick_tenms == 0) << 30;
                noref | skew | self.cfg.systick_tenms & 0x00FF_FFFF
            }
            0x100..=0x11F => self.nvic.irq_bits(&self.nvic.enabled, irq_reg(0x100)),
            0x180..=0x19F => self.nvic.irq_bits(&self.nvic.enabled, irq_reg(0x180)),
            0x200..=0x21F => self.nvic.irq_bits(&self.nvic.pending, irq_reg(0x200)),
            0x280..=0x29F => self.nvic.irq_bits(&self.nvic.pending, irq_reg(0x280)),
            0x300..=0x31F => self.nvic.irq_bits(&self.nvic.active, irq_reg(0x300)),
            0x400..=0x4EF => self.read_priority_word((off - 0x400) as u16 + exc::IRQ0),
            0xD00 => CPUID,
            0xD04 => self.icsr(),
            0xD08 => self.scb.vtor,
            0xD0C => 0xFA05 << 16 | u32::from(self.scb.prigroup) << 8,
            0xD10 => self.scb.scr,
            0xD14 => self.scb.ccr,
            0xD18..=0xD23 => self.read_priority_word((off - 0xD14) as u16),
            0xD24 => self.shcsr(),
            0xD28 => self.scb.cfsr,
            0xD2C => self.scb.hfsr,
            0xD30 => self.scb.dfsr,
            0xD34 => self.scb.mmfar,
            0xD38 => self.scb.bfar,
            0xD3C => self.scb.afsr,
            0xD40..=0xD73 => ID_REGS
                .get(((off - 0xD40) / 4) as usize)
                .copied()
                .unwrap_or(0),
            0xD88 => self.scb.cpacr,
            0xD90 => 8 << 8,
            0xD94 => self.mpu.ctrl,
            0xD98 => self.mpu.rnr,
            0xD9C | 0xDA4 | 0xDAC | 0xDB4 => {
                let r = (self.mpu.rnr & 7) as usize;
                self.mpu.rbar.get(r).copied().unwrap_or(0) | (r as u32)
            }
            0xDA0 | 0xDA8 | 0xDB0 | 0xDB8 => self
                .mpu
                .rasr
                .get((self.mpu.rnr & 7) as usize)
                .copied()
                .unwrap_or(0),
            0xDFC => self.debug.demcr,
            0xF34 => self.scb.fpccr,
            0xF38 => self.scb.fpcar,
            0xF3C => self.scb.fpdscr,
            0xF40 => MVFR0,
            0xF44 => MVFR1,
            _ => 0,
        }
    }

    fn set_irq_bits(&mut self, k: usize, v: u32, f: impl Fn(&mut crate::nvic::Nvic, u16)) {
        for i in 0..32u32 {
            let irq = k as u32 * 32 + i;
            if v >> i & 1 != 0 && irq < u32::from(self.nvic.irqs()) {
                f(&mut self.nvic, exc::IRQ0 + irq as u16);
            }
        }
    }

    fn scb_write(&mut self, off: u32, v: u32) {
        let irq_reg = |base: u32| ((off - base) / 4) as usize;
        let cycles = self.clock.cycles;
        match off {
            0x008 => self.scb.actlr = v & 0x307,
            0x010 => self.systick.write_csr(v, cycles, self.cfg.systick_ref_div),
            0x014 => self.systick.write_rvr(v, cycles),
            0x018 => self.systick.write_cvr(cycles),
            0x100..=0x11F => self.set_irq_bits(irq_reg(0x100), v, |n, e| n.set_enabled(e, true)),
            0x180..=0x19F => self.set_irq_bits(irq_reg(0x180), v, |n, e| n.set_enabled(e, false)),
            0x200..=0x21F => {
                self.set_irq_bits(irq_reg(0x200), v, |n, e| n.set_pending(e, true));
                if v != 0 {
                    self.new_pending();
                }
            }
            0x280..=0x29F => {
                self.set_irq_bits(irq_reg(0x280), v, |n, e| n.set_pending(e, false));
                if self.nvic.relatch() {
                    self.new_pending();
                }
            }
            0xD04 => self.icsr_write(v),
            0xD08 => self.scb.vtor = v & 0xFFFF_FF80,
            0xD0C if v >> 16 == 0x05FA => {
                self.scb.prigroup = (v >> 8 & 7) as u8;
                if v & (1 << 2) != 0 {
                    self.reset_request = Some(crate::cpu::ResetKind::SysResetReq);
                }
            }
            0xD10 => self.scb.scr = v & 0x16,
            0xD14 => self.scb.ccr = v & CCR_MASK,
            0xD24 => self.shcsr_write(v),
            0xD28 => self.scb.cfsr &= !v,
            0xD2C => self.scb.hfsr &= !v,
            0xD30 => self.scb.dfsr &= !v,
            0xD34 => self.scb.mmfar = v,
            0xD38 => self.scb.bfar = v,
            0xD3C => self.scb.afsr &= !v,
            0xD88 => {
                self.scb.cpacr = v & 0x00F0_0000;
                self.fp_ready = false;
            }
            0xD94 => self.mpu.ctrl = v & 7,
            0xD98 => self.mpu.rnr = v & 0xFF,
            0xD9C | 0xDA4 | 0xDAC | 0xDB4 => {
                if v & 0x10 != 0 {
                    self.mpu.rnr = v & 7;
                }
                if let Some(r) = self.mpu.rbar.get_mut((self.mpu.rnr & 7) as usize) {
                    *r = v & !0x1F;
                }
            }
            0xDA0 | 0xDA8 | 0xDB0 | 0xDB8 => {
                if let Some(r) = self.mpu.rasr.get_mut((self.mpu.rnr & 7) as usize) {
                    *r = v;
                }
            }
            0xDFC => {
                self.cyccnt_rebase();
                self.debug.demcr = v & 0x010F_07F1;
            }
            0xF00 => {
                let irq = v & 0x1FF;
                if irq < u32::from(self.nvic.irqs()) {
                    self.nvic.set_pending(exc::IRQ0 + irq as u16, true);
                    self.new_pending();
                }
            }
            0xF34 => {
                self.scb.fpccr = v & 0xC000_017B;
                self.fp_ready = false;
            }
            0xF38 => self.scb.fpcar = v & !7,
            0xF3C => self.scb.fpdscr = v & 0x07C0_0000,
            _ => {}
        }
    }

    fn icsr_write(&mut self, v: u32) {
        if v & (1 << 31) != 0 {
            self.nvic.set_pending(exc::NMI, true);
        }
        if v & (1 << 28) != 0 {
            self.nvic.set_pending(exc::PENDSV, true);
        } else if v & (1 << 27) != 0 {
            self.nvic.set_pending(exc::PENDSV, false);
        }
        if v & (1 << 26) != 0 {
            self.nvic.set_pending(exc::SYSTICK, true);
        } else if v & (1 << 25) != 0 {
            self.nvic.set_pending(exc::SYSTICK, false);
        }
    }

    fn shcsr_write(&mut self, v: u32) {
        let n = &mut self.nvic;
        let b = |i: u32| v >> i & 1 != 0;
        n.set_active(exc::MEM_MANAGE, b(0));
        n.set_active(exc::BUS_FAULT, b(1));
        n.set_active(exc::USAGE_FAULT, b(3));
        n.set_active(exc::SVCALL, b(7));
        n.set_active(12, b(8));
        n.set_active(exc::PENDSV, b(10));
        n.set_active(exc::SYSTICK, b(11));
        n.set_pending(exc::USAGE_FAULT, b(12));
        n.set_pending(exc::MEM_MANAGE, b(13));
        n.set_pending(exc::BUS_FAULT, b(14));
        n.set_pending(exc::SVCALL, b(15));
        n.set_enabled(exc::MEM_MANAGE, v & shcsr::MEMFAULTENA != 0);
        n.set_enabled(exc::BUS_FAULT, v & shcsr::BUSFAULTENA != 0);
        n.set_enabled(exc::USAGE_FAULT, v & shcsr::USGFAULTENA != 0);
    }

    /// Whether the current access is privileged (Handler mode, or Thread mode with nPRIV
    /// clear).
    pub(crate) fn privileged(&self) -> bool {
        self.ipsr != 0 || self.control & control::NPRIV == 0
    }

    /// Handles SysTick wraps due by now: COUNTFLAG, and the exception when TICKINT is set.
    pub(crate) fn systick_catch_up(&mut self) {
        if self.systick.fire_due(self.clock.cycles) && self.systick.csr & systick::TICKINT != 0 {
            self.nvic.set_pending(exc::SYSTICK, true);
        }
    }
}
