//! Synchronous faults: which status bits they set (CFSR, HFSR, the fault address
//! registers), which exception they raise, and escalation to HardFault or lockup (ARM ARM
//! B1.5.6 "Exception priorities and preemption", B3.2.15 "Configurable Fault Status").

use crate::bus::Bus;
use crate::cpu::{Cpu, RunState, Stop};
use crate::nvic::exc;

/// A fault an instruction (or its fetch) raised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Fault {
    /// UNDEFINED or UNPREDICTABLE encoding (UFSR.UNDEFINSTR).
    Undefined,
    /// Executing with EPSR.T clear (UFSR.INVSTATE).
    InvState,
    /// An illegal EXC_RETURN (UFSR.INVPC).
    InvPc,
    /// A coprocessor instruction with the coprocessor absent or disabled (UFSR.NOCP).
    NoCp,
    /// An unaligned access that must be aligned (UFSR.UNALIGNED).
    Unaligned,
    /// SDIV/UDIV by zero with CCR.DIV_0_TRP (UFSR.DIVBYZERO).
    DivByZero,
    /// A data access the bus refused (BFSR.PRECISERR, BFAR).
    BusData(u32),
    /// An instruction fetch the bus refused (BFSR.IBUSERR).
    BusInstr,
    /// Executing from an execute-never region (MMFSR.IACCVIOL).
    MemInstr,
    /// A BKPT with no debugger to halt (HFSR.DEBUGEVT).
    Breakpoint,
}

/// CFSR bits.
pub(crate) mod cfsr {
    pub const IACCVIOL: u32 = 1 << 0;
    pub const IBUSERR: u32 = 1 << 8;
    pub const PRECISERR: u32 = 1 << 9;
    pub const UNSTKERR: u32 = 1 << 11;
    pub const STKERR: u32 = 1 << 12;
    pub const BFARVALID: u32 = 1 << 15;
    pub const UNDEFINSTR: u32 = 1 << 16;
    pub const INVSTATE: u32 = 1 << 17;
    pub const INVPC: u32 = 1 << 18;
    pub const NOCP: u32 = 1 << 19;
    pub const UNALIGNED: u32 = 1 << 24;
    pub const DIVBYZERO: u32 = 1 << 25;
}

/// HFSR bits.
pub(crate) mod hfsr {
    pub const VECTTBL: u32 = 1 << 1;
    pub const FORCED: u32 = 1 << 30;
    pub const DEBUGEVT: u32 = 1 << 31;
}

/// SHCSR enable bits of the configurable faults.
pub(crate) mod shcsr {
    pub const MEMFAULTENA: u32 = 1 << 16;
    pub const BUSFAULTENA: u32 = 1 << 17;
    pub const USGFAULTENA: u32 = 1 << 18;
}

impl Cpu {
    /// Raises a synchronous fault for the instruction at `self.pc` (which has not
    /// completed): records its status, then pends the fault's exception, HardFault when
    /// the fault is disabled or cannot preempt, or locks up when not even HardFault can.
    pub(crate) fn raise_fault<B: Bus>(&mut self, bus: &mut B, fault: Fault) {
        let _ = bus;
        let target = match fault {
            Fault::Undefined => self.usage(cfsr::UNDEFINSTR),
            Fault::InvState => self.usage(cfsr::INVSTATE),
            Fault::InvPc => self.usage(cfsr::INVPC),
            Fault::NoCp => self.usage(cfsr::NOCP),
            Fault::Unaligned => self.usage(cfsr::UNALIGNED),
            Fault::DivByZero => self.usage(cfsr::DIVBYZERO),
            Fault::BusData(addr) => {
                self.scb.cfsr |= cfsr::PRECISERR | cfsr::BFARVALID;
                self.scb.bfar = addr;
                exc::BUS_FAULT
            }
            Fault::BusInstr => {
                self.scb.cfsr |= cfsr::IBUSERR;
                exc::BUS_FAULT
            }
            Fault::MemInstr => {
                self.scb.cfsr |= cfsr::IACCVIOL;
                exc::MEM_MANAGE
            }
            Fault::Breakpoint => {
                self.scb.hfsr |= hfsr::DEBUGEVT;
                self.scb.dfsr |= 1 << 1;
                exc::HARD_FAULT
            }
        };
        self.pend_synchronous(target);
    }

    fn usage(&mut self, bit: u32) -> u16 {
        self.scb.cfsr |= bit;
        exc::USAGE_FAULT
    }

    /// Pends a synchronous exception (a fault or SVCall): escalated to HardFault when it is
    /// disabled or its priority cannot preempt the current execution priority; lockup when
    /// HardFault cannot either.
    pub(crate) fn pend_synchronous(&mut self, n: u16) {
        let current = self.execution_priority();
        let enabled = self.nvic.is_enabled(n);
        let target = if enabled && self.group_priority(self.nvic.priority(n)) < current {
            n
        } else {
            if n != exc::HARD_FAULT {
                self.scb.hfsr |= hfsr::FORCED;
            }
            exc::HARD_FAULT
        };
        if target == exc::HARD_FAULT && current <= -1 {
            self.lockup();
            return;
        }
        self.nvic.set_pending(target, true);
        self.stop_at = 0;
    }

    /// Enters lockup: execution stops until a reset.
    pub(crate) fn lockup(&mut self) {
        self.state = RunState::LockedUp;
        self.pending_stop = Some(Stop::Lockup { pc: self.pc });
        self.stop_at = 0;
    }
}
