//! Register access for tests, tracing and the runners ([`Cpu::read_reg`],
//! [`Cpu::write_reg`]): the same view a debugger has.

use crate::cpu::{Cpu, Reg};

impl Cpu {
    /// The value of a register. `Reg::R(15)` is the address of the next instruction.
    pub fn read_reg(&self, r: Reg) -> u32 {
        match r {
            Reg::R(15) => self.pc,
            Reg::R(n) => self.reg(n),
            Reg::Xpsr => self.xpsr(),
            Reg::Msp => self.msp(),
            Reg::Psp => self.psp(),
            Reg::Primask => u32::from(self.primask),
            Reg::Basepri => u32::from(self.basepri),
            Reg::Faultmask => u32::from(self.faultmask),
            Reg::Control => self.control,
            Reg::S(n) => self.s.get(usize::from(n & 31)).copied().unwrap_or(0),
            Reg::Fpscr => self.fpscr,
        }
    }

    /// Sets a register. Writing `Reg::R(15)` moves execution (bit 0 ignored); `Reg::Xpsr`
    /// sets the flags, GE, IT and T bits (not the exception number).
    pub fn write_reg(&mut self, r: Reg, v: u32) {
        match r {
            Reg::R(15) => {
                self.pc = v & !1;
                self.refill = true;
            }
            Reg::R(13) => {
                self.r[13] = v & !3;
                self.note_sp(v & !3);
            }
            Reg::R(n) => {
                if let Some(x) = self.r.get_mut(usize::from(n)) {
                    *x = v;
                }
            }
            Reg::Xpsr => {
                self.set_apsr(v, true, true);
                self.thumb = v & (1 << 24) != 0;
                self.it = ((v >> 25 & 3) | (v >> 8 & 0xFC)) as u8;
            }
            Reg::Msp => self.set_msp(v),
            Reg::Psp => self.set_psp(v),
            Reg::Primask => self.primask = v & 1 != 0,
            Reg::Basepri => self.basepri = v as u8,
            Reg::Faultmask => self.faultmask = v & 1 != 0,
            Reg::Control => {
                self.control = v & 7;
                let psp = self.ipsr == 0 && v & 2 != 0;
                self.select_sp(psp);
                self.fp_ready = false;
            }
            Reg::S(n) => {
                if let Some(x) = self.s.get_mut(usize::from(n & 31)) {
                    *x = v;
                }
            }
            Reg::Fpscr => self.fpscr = v & crate::exec::fp::FPSCR_MASK,
        }
        self.stop_at = 0;
    }
}
