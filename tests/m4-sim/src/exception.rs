//! Exception entry and return (ARM ARM B1.5.6–B1.5.8): priorities and preemption with
//! PRIMASK/FAULTMASK/BASEPRI and PRIGROUP, stacking of the basic or extended (FP) frame
//! with 8-byte alignment, EXC_RETURN, tail-chaining, sleep-on-exit, and the wake-up
//! conditions of WFI and WFE.
//!
//! Lazy FP stacking is modelled as eager: the FP part of the frame is written on entry and
//! read on return, which leaves the same architectural state (FPCCR.LSPACT stays 0).

use crate::bus::{Bus, Width};
use crate::cpu::{Cpu, RunState};
use crate::fault::{Fault, cfsr, hfsr};
use crate::nvic::exc;

/// CONTROL bits.
pub(crate) mod control {
    pub const NPRIV: u32 = 1 << 0;
    pub const SPSEL: u32 = 1 << 1;
    pub const FPCA: u32 = 1 << 2;
}

/// FPCCR bits.
pub(crate) mod fpccr {
    pub const LSPEN: u32 = 1 << 30;
    pub const ASPEN: u32 = 1 << 31;
}

const FRAME_BASIC: u32 = 0x20;
const FRAME_FP: u32 = 0x68;

impl Cpu {
    /// A priority with its subpriority bits removed (AIRCR.PRIGROUP).
    pub(crate) fn group_priority(&self, prio: i16) -> i16 {
        if prio < 0 {
            return prio;
        }
        let sub_mask = (2i16 << self.scb.prigroup) - 1;
        prio & !sub_mask
    }

    /// The current execution priority (B1.5.4), with PRIMASK counted or not.
    fn priority_with(&self, primask: bool) -> i16 {
        let active = self.nvic.highest_active_priority();
        let active = if active >= 256 {
            256
        } else {
            self.group_priority(active)
        };
        let mut boosted = 256;
        if self.basepri != 0 {
            boosted = self.group_priority(i16::from(self.basepri));
        }
        if primask && self.primask {
            boosted = 0;
        }
        if self.faultmask {
            boosted = -1;
        }
        boosted.min(active)
    }

    /// The current execution priority (B1.5.4).
    pub(crate) fn execution_priority(&self) -> i16 {
        self.priority_with(true)
    }

    /// The pending exception that would preempt now, if any.
    fn preempting(&self, primask: bool) -> Option<u16> {
        let (n, prio) = self.nvic.best_pending()?;
        (self.group_priority(prio) < self.priority_with(primask)).then_some(n)
    }

    /// Wakes a sleeping core when it should, then takes the highest-priority pending
    /// exception if it preempts.
    pub(crate) fn take_pending_exception<B: Bus>(&mut self, bus: &mut B) {
        match self.state {
            RunState::SleepWfi if self.preempting(false).is_some() => self.wake(bus),
            RunState::SleepWfe if self.event || self.preempting(true).is_some() => {
                self.event = false;
                self.wake(bus);
            }
            _ => {}
        }
        if self.state != RunState::Running {
            return;
        }
        if let Some(n) = self.preempting(true) {
            let return_address = self.pc;
            self.enter_exception(bus, n, return_address);
        }
    }

    /// The xPSR value as stacked: flags, GE, IT, T, exception number.
    pub(crate) fn xpsr(&self) -> u32 {
        let f = &self.flags;
        u32::from(f.n) << 31
            | u32::from(f.z) << 30
            | u32::from(f.c) << 29
            | u32::from(f.v) << 28
            | u32::from(f.q) << 27
            | u32::from(self.it & 3) << 25
            | u32::from(self.thumb) << 24
            | u32::from(f.ge & 0xF) << 16
            | u32::from(self.it >> 2) << 10
            | u32::from(self.ipsr)
    }

    /// Sets the APSR flags from bits 31:27 and 19:16 of `v`.
    pub(crate) fn set_apsr(&mut self, v: u32, flags: bool, ge: bool) {
        if flags {
            self.flags.n = v >> 31 & 1 != 0;
            self.flags.z = v >> 30 & 1 != 0;
            self.flags.c = v >> 29 & 1 != 0;
            self.flags.v = v >> 28 & 1 != 0;
            self.flags.q = v >> 27 & 1 != 0;
        }
        if ge {
            self.flags.ge = (v >> 16 & 0xF) as u8;
        }
    }

    /// Switches R13 between MSP and PSP.
    pub(crate) fn select_sp(&mut self, psp: bool) {
        if psp != self.on_psp {
            std::mem::swap(&mut self.r[13], &mut self.sp_other);
            self.on_psp = psp;
        }
    }

    /// Stacks a frame (PushStack) and enters the handler of exception `n`
    /// (ExceptionTaken); `return_address` is where the interrupted code resumes.
    pub(crate) fn enter_exception<B: Bus>(&mut self, bus: &mut B, n: u16, return_address: u32) {
        let fp_frame = self.control & control::FPCA != 0;
        let frame_size = if fp_frame { FRAME_FP } else { FRAME_BASIC };
        let force_align = fp_frame || self.scb.ccr & (1 << 9) != 0;
        let sp = self.r[13];
        let realign = force_align && sp & 4 != 0;
        let align_mask = if force_align { !7 } else { !3 };
        let frame = sp.wrapping_sub(frame_size) & align_mask;
        self.r[13] = frame;
        self.note_sp(frame);
        let psr = self.xpsr() & !(1 << 9) | u32::from(realign) << 9;
        let words = [
            self.r[0],
            self.r[1],
            self.r[2],
            self.r[3],
            self.r[12],
            self.r[14],
            return_address,
            psr,
        ];
        let mut stack_error = false;
        for (i, w) in (0u32..).zip(words) {
            stack_error |= self.stack_write(bus, frame.wrapping_add(4 * i), w);
        }
        let mut cycles = crate::cycles::ENTRY;
        if fp_frame {
            for i in 0..16u32 {
                let v = self.s.get(i as usize).copied().unwrap_or(0);
                stack_error |= self.stack_write(bus, frame.wrapping_add(0x20 + 4 * i), v);
            }
            stack_error |= self.stack_write(bus, frame.wrapping_add(0x60), self.fpscr);
            if self.scb.fpccr & fpccr::LSPEN == 0 {
                cycles += crate::cycles::ENTRY_FP_EAGER;
            }
        }
        let mode_bits = if self.ipsr != 0 {
            0x1
        } else if self.on_psp {
            0xD
        } else {
            0x9
        };
        let exc_return = 0xFFFF_FFE0 | u32::from(!fp_frame) << 4 | mode_bits;
        self.clock.cycles += cycles;
        if stack_error {
            self.scb.cfsr |= cfsr::STKERR;
            self.nvic.set_pending(exc::BUS_FAULT, true);
        }
        self.activate(bus, n, exc_return);
    }

    /// ExceptionTaken: LR, IPSR, ITSTATE, SP selection, FPCA, active and pending bits, the
    /// vector fetch.
    fn activate<B: Bus>(&mut self, bus: &mut B, n: u16, exc_return: u32) {
        self.r[14] = exc_return;
        self.ipsr = n;
        self.it = 0;
        self.select_sp(false);
        self.control &= !(control::FPCA | control::SPSEL);
        self.fp_ready = false;
        self.nvic.set_active(n, true);
        self.nvic.set_pending(n, false);
        self.exclusive = false;
        self.event = true;
        self.refill = true;
        if let Some(count) = self.exceptions.get_mut(usize::from(n)) {
            *count += 1;
        }
        let vector_addr = self.scb.vtor.wrapping_add(4 * u32::from(n));
        let now = self.clock.now_ns();
        match bus.read(vector_addr, Width::Word, now) {
            Ok(vector) => {
                self.clock.cycles += u64::from(bus.access_stall(vector_addr, false));
                self.thumb = vector & 1 != 0;
                self.pc = vector & !1;
                // Entered from inside an instruction (a tail-chain), the run loop moves
                // to `next_pc`.
                self.next_pc = self.pc;
            }
            Err(_) => {
                // A vector that cannot be read is a HardFault (VECTTBL), taken from here;
                // failing that in HardFault or NMI is lockup.
                self.scb.hfsr |= hfsr::VECTTBL;
                if n == exc::HARD_FAULT || n == exc::NMI {
                    self.lockup();
                } else {
                    self.nvic.set_active(n, false);
                    self.nvic.set_pending(exc::HARD_FAULT, true);
                }
            }
        }
        self.stop_at = 0;
    }

    /// One word of an exception frame; returns true on a bus error.
    fn stack_write<B: Bus>(&mut self, bus: &mut B, addr: u32, value: u32) -> bool {
        self.store_raw(bus, addr, Width::Word, value).is_err()
    }

    /// ExceptionReturn for the EXC_RETURN value `exc_return` (from a BX, POP, LDM or LDR
    /// into the PC in Handler mode).
    pub(crate) fn exception_return<B: Bus>(
        &mut self,
        bus: &mut B,
        exc_return: u32,
    ) -> Result<(), Fault> {
        let returning = self.ipsr;
        let to_thread = match exc_return & 0xF {
            0x1 => false,
            0x9 | 0xD => true,
            _ => return Err(Fault::InvPc),
        };
        if exc_return & 0x0FFF_FFE0 != 0x0FFF_FFE0 || !self.nvic.is_active(returning) {
            return Err(Fault::InvPc);
        }
        let nested = self.nvic.active_count();
        if (to_thread && nested != 1 && self.scb.ccr & 1 == 0) || (!to_thread && nested == 1) {
            return Err(Fault::InvPc);
        }
        // Deactivate.
        self.nvic.set_active(returning, false);
        if returning != exc::NMI {
            self.faultmask = false;
        }
        if self.nvic.relatch() {
            self.new_pending();
        }
        self.exclusive = false;
        self.event = true;
        self.stop_at = 0;
        // Tail-chain into a pending exception that preempts what we return to.
        let use_psp = exc_return & 4 != 0;
        let fp_frame = exc_return & 0x10 == 0;
        // The priority we return to: the remaining active exceptions and the masks.
        let return_priority = self.execution_priority();
        let chain = self
            .nvic
            .best_pending()
            .filter(|&(_, p)| self.group_priority(p) < return_priority);
        if let Some((n, _)) = chain {
            self.clock.cycles += crate::cycles::TAIL_CHAIN;
            self.activate(bus, n, exc_return);
            return Ok(());
        }
        self.pop_frame(bus, use_psp, fp_frame, to_thread);
        if to_thread && self.scb.scr & 2 != 0 {
            self.sleep(bus, RunState::SleepWfi);
        }
        Ok(())
    }

    /// PopStack and the mode change of an exception return.
    fn pop_frame<B: Bus>(&mut self, bus: &mut B, use_psp: bool, fp_frame: bool, to_thread: bool) {
        // Select the stack the frame is on; Handler mode always uses MSP.
        self.select_sp(use_psp);
        let frame = self.r[13];
        let mut words = [0u32; 8];
        let mut error = false;
        for (i, w) in (0u32..).zip(words.iter_mut()) {
            match self.load_raw(bus, frame.wrapping_add(4 * i), Width::Word) {
                Ok(v) => *w = v,
                Err(_) => error = true,
            }
        }
        let mut cycles = crate::cycles::RETURN;
        if fp_frame {
            for i in 0..16u32 {
                if let Ok(v) = self.load_raw(bus, frame.wrapping_add(0x20 + 4 * i), Width::Word) {
                    if let Some(s) = self.s.get_mut(i as usize) {
                        *s = v;
                    }
                } else {
                    error = true;
                }
            }
            match self.load_raw(bus, frame.wrapping_add(0x60), Width::Word) {
                Ok(v) => self.fpscr = v & crate::exec::fp::FPSCR_MASK,
                Err(_) => error = true,
            }
            cycles += crate::cycles::RETURN_FP;
        }
        self.clock.cycles += cycles;
        let [r0, r1, r2, r3, r12, lr, pc, psr] = words;
        self.r[0] = r0;
        self.r[1] = r1;
        self.r[2] = r2;
        self.r[3] = r3;
        self.r[12] = r12;
        self.r[14] = lr;
        self.pc = pc & !1;
        self.next_pc = self.pc;
        self.refill = true;
        let frame_size = if fp_frame { FRAME_FP } else { FRAME_BASIC };
        let force_align = fp_frame || self.scb.ccr & (1 << 9) != 0;
        let realign = if force_align && psr & (1 << 9) != 0 {
            4
        } else {
            0
        };
        self.r[13] = frame.wrapping_add(frame_size) | realign;
        self.set_apsr(psr, true, true);
        self.ipsr = if to_thread { 0 } else { (psr & 0x1FF) as u16 };
        self.thumb = psr & (1 << 24) != 0;
        self.it = ((psr >> 25 & 3) | (psr >> 8 & 0xFC)) as u8;
        if fp_frame {
            self.control |= control::FPCA;
        } else {
            self.control &= !control::FPCA;
        }
        if to_thread {
            self.control = self.control & !control::SPSEL | u32::from(use_psp) << 1;
        }
        self.fp_ready = false;
        if error {
            self.scb.cfsr |= cfsr::UNSTKERR;
            self.nvic.set_pending(exc::BUS_FAULT, true);
        }
        if (psr & 0x1FF == 0) != to_thread {
            // A frame whose IPSR disagrees with the return mode: INVPC, raised at the
            // return address.
            self.scb.cfsr |= cfsr::INVPC;
            self.pend_synchronous(exc::USAGE_FAULT);
        }
    }
}
