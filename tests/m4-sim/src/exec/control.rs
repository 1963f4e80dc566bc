//! System instructions: MRS/MSR on the special registers (B5.2.2, B5.2.3), CPS, BKPT.

use super::Trap;
use crate::bus::Bus;
use crate::cpu::{Cpu, Stop};
use crate::exception::control;
use crate::fault::Fault;

impl Cpu {
    /// MRS: the value of special register `sysm`.
    pub(crate) fn read_special(&self, sysm: u8) -> u32 {
        let privileged = self.privileged();
        match sysm {
            0..=7 => {
                let mut v = 0;
                if sysm & 1 != 0 {
                    v |= u32::from(self.ipsr);
                }
                if sysm & 4 == 0 {
                    v |= self.xpsr() & 0xF80F_0000;
                }
                // EPSR reads as zero through MRS.
                v
            }
            8 if privileged => self.msp(),
            9 if privileged => self.psp(),
            16 => u32::from(self.primask),
            17 | 18 => u32::from(self.basepri),
            19 => u32::from(self.faultmask),
            20 => self.control & (control::NPRIV | control::SPSEL | control::FPCA),
            _ => 0,
        }
    }

    /// The main stack pointer, wherever it is held.
    pub(crate) fn msp(&self) -> u32 {
        if self.on_psp {
            self.sp_other
        } else {
            self.r[13]
        }
    }

    /// The process stack pointer, wherever it is held.
    pub(crate) fn psp(&self) -> u32 {
        if self.on_psp {
            self.r[13]
        } else {
            self.sp_other
        }
    }

    pub(crate) fn set_msp(&mut self, v: u32) {
        let v = v & !3;
        self.note_sp(v);
        if self.on_psp {
            self.sp_other = v;
        } else {
            self.r[13] = v;
        }
    }

    pub(crate) fn set_psp(&mut self, v: u32) {
        let v = v & !3;
        self.note_sp(v);
        if self.on_psp {
            self.r[13] = v;
        } else {
            self.sp_other = v;
        }
    }

    /// MSR: writes special register `sysm` (APSR fields per `mask`).
    pub(crate) fn write_special(&mut self, sysm: u8, mask: u8, v: u32) {
        let privileged = self.privileged();
        match sysm {
            0..=3 => self.set_apsr(v, mask & 2 != 0, mask & 1 != 0),
            _ if !privileged => {}
            8 => self.set_msp(v),
            9 => self.set_psp(v),
            16 => self.primask = v & 1 != 0,
            17 => self.basepri = (v & 0xFF) as u8 & self.prio_mask(),
            18 => {
                let new = (v & 0xFF) as u8 & self.prio_mask();
                if new != 0 && (new < self.basepri || self.basepri == 0) {
                    self.basepri = new;
                }
            }
            19 if self.execution_priority() > -1 => self.faultmask = v & 1 != 0,
            20 => {
                self.control = self.control & !control::NPRIV | v & control::NPRIV;
                if self.ipsr == 0 {
                    self.control = self.control & !control::SPSEL | v & control::SPSEL;
                    self.select_sp(v & control::SPSEL != 0);
                }
                self.control = self.control & !control::FPCA | v & control::FPCA;
                self.fp_ready = false;
            }
            _ => {}
        }
        self.stop_at = 0;
    }

    /// The implemented bits of a priority byte.
    fn prio_mask(&self) -> u8 {
        (0xFF00u16 >> self.cfg.prio_bits.clamp(2, 8)) as u8
    }

    /// CPSIE/CPSID (ignored when unprivileged).
    pub(crate) fn exec_cps(&mut self, disable: bool, primask: bool, faultmask: bool) {
        if !self.privileged() {
            return;
        }
        if primask {
            self.primask = disable;
        }
        if faultmask && (!disable || self.execution_priority() > -1) {
            self.faultmask = disable;
        }
        self.stop_at = 0;
    }

    /// BKPT: semihosting for 0xAB, else a halt (with a debugger, as configured) or a
    /// HardFault (DEBUGEVT).
    pub(crate) fn exec_bkpt<B: Bus>(&mut self, bus: &mut B, imm: u8) -> Result<(), Trap> {
        if imm == 0xAB {
            return match self.semihost(bus)? {
                Some(code) => Err(Trap::Stop(Stop::Exit { code })),
                None => Ok(()),
            };
        }
        if self.cfg.halt_on_bkpt {
            return Err(Trap::Stop(Stop::Breakpoint { pc: self.pc, imm }));
        }
        Err(Fault::Breakpoint.into())
    }
}
