//! The processor: architectural state, the public API, and the run loop that executes
//! instructions, lets virtual time pass and takes exceptions.
//!
//! The hot loop ([`Cpu::run_until`]) does one compare per instruction against `stop_at`,
//! the earliest cycle at which anything but the next instruction needs attention (the
//! deadline, the bus's next event, a SysTick wrap, an exception state change, a sleep
//! request). Everything else happens in [`Cpu::service`].

use std::collections::BTreeSet;

use crate::bus::{Bus, ResetCause};
use crate::cache::{Cache, Slot};
use crate::clock::Clock;
use crate::config::Config;
use crate::exec::Trap;
use crate::fault::Fault;
use crate::insn::Insn;
use crate::nvic::Nvic;
use crate::scs::{Debug, Mpu, Scb};
use crate::systick::SysTick;

/// SCR.SEVONPEND.
const SEVONPEND: u32 = 1 << 4;

/// Why [`Cpu::run_until`] returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// Virtual time reached the deadline.
    Deadline,
    /// The program called semihosting SYS_EXIT or SYS_EXIT_EXTENDED; `code` is 0 for
    /// `ADP_Stopped_ApplicationExit` (with subcode 0) and the reason or subcode otherwise.
    Exit {
        /// The exit status.
        code: u32,
    },
    /// A BKPT other than the semihosting one, with [`Config::halt_on_bkpt`] set. The PC has
    /// moved past it.
    Breakpoint {
        /// Address of the BKPT instruction.
        pc: u32,
        /// Its immediate.
        imm: u8,
    },
    /// A fault while in HardFault or NMI (or with FAULTMASK set): the core locked up.
    /// Further calls let time pass until a reset.
    Lockup {
        /// The address of the faulting instruction.
        pc: u32,
    },
    /// The PC reached an address registered with [`Cpu::add_pc_hook`]; the instruction
    /// there has not executed yet (the next call executes it without stopping again).
    Hook {
        /// The hooked address.
        pc: u32,
    },
}

/// A register for [`Cpu::read_reg`] and [`Cpu::write_reg`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reg {
    /// R0–R15 (13 = the current SP, 14 = LR, 15 = the PC of the next instruction).
    R(u8),
    /// The combined program status register.
    Xpsr,
    /// The main stack pointer.
    Msp,
    /// The process stack pointer.
    Psp,
    /// PRIMASK (bit 0).
    Primask,
    /// BASEPRI.
    Basepri,
    /// FAULTMASK (bit 0).
    Faultmask,
    /// CONTROL (nPRIV, SPSEL, FPCA).
    Control,
    /// S0–S31.
    S(u8),
    /// The floating-point status and control register.
    Fpscr,
}

/// Counters over the life of a [`Cpu`] (they survive resets). Exceptions taken per
/// exception number are [`Cpu::exceptions_taken`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stats {
    /// Instructions executed (a condition-failed instruction in an IT block counts, as in
    /// QEMU's count).
    pub instructions: u64,
    /// Cycles spent executing (including exception entry and return, stalls).
    pub cycles_active: u64,
    /// Cycles spent asleep (WFI, WFE, sleep-on-exit, lockup).
    pub cycles_asleep: u64,
    /// The lowest value either stack pointer held (`u32::MAX` before any).
    pub lowest_sp: u32,
}

/// The fault status registers (SCB CFSR, HFSR, MMFAR, BFAR), for reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaultStatus {
    /// Configurable fault status (MMFSR, BFSR, UFSR).
    pub cfsr: u32,
    /// HardFault status.
    pub hfsr: u32,
    /// MemManage fault address.
    pub mmfar: u32,
    /// BusFault address.
    pub bfar: u32,
}

/// What the core is doing between instructions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RunState {
    Running,
    /// WFI or sleep-on-exit.
    SleepWfi,
    SleepWfe,
    LockedUp,
}

/// Where a pending system reset comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ResetKind {
    /// The bus asked ([`Bus::take_reset_request`]).
    Bus(ResetCause),
    /// The program set AIRCR.SYSRESETREQ.
    SysResetReq,
}

/// The condition flags and the DSP extension's Q and GE bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Flags {
    pub n: bool,
    pub z: bool,
    pub c: bool,
    pub v: bool,
    pub q: bool,
    pub ge: u8,
}

/// A Cortex-M4F core.
pub struct Cpu {
    pub(crate) cfg: Config,
    /// R0–R15; R13 is the SP in use, R15 holds the PC as instructions read it (address + 4).
    pub(crate) r: [u32; 16],
    /// The stack pointer not in use (PSP while on MSP and vice versa).
    pub(crate) sp_other: u32,
    /// Whether R13 currently is the process stack pointer.
    pub(crate) on_psp: bool,
    pub(crate) flags: Flags,
    /// ITSTATE: condition in bits 7:4, mask in 3:0; 0 outside an IT block.
    pub(crate) it: u8,
    /// Whether the instruction executing is inside an IT block.
    pub(crate) in_it: bool,
    pub(crate) ipsr: u16,
    /// EPSR.T: executing a Thumb instruction with it clear is an INVSTATE fault.
    pub(crate) thumb: bool,
    pub(crate) primask: bool,
    pub(crate) faultmask: bool,
    pub(crate) basepri: u8,
    /// CONTROL: bit 0 nPRIV, bit 1 SPSEL, bit 2 FPCA.
    pub(crate) control: u32,
    pub(crate) s: [u32; 32],
    pub(crate) fpscr: u32,
    /// Whether FP instructions may run without the checks of `ExecuteFPCheck`.
    pub(crate) fp_ready: bool,
    /// Address of the instruction executing (or next to execute between instructions).
    pub(crate) pc: u32,
    /// Where execution continues after the current instruction.
    pub(crate) next_pc: u32,
    /// The next fetch is not sequential (taken branch, exception): pipeline refill.
    pub(crate) refill: bool,
    pub(crate) exclusive: bool,
    pub(crate) event: bool,
    pub(crate) state: RunState,
    pub(crate) nvic: Nvic,
    pub(crate) scb: Scb,
    pub(crate) systick: SysTick,
    pub(crate) mpu: Mpu,
    pub(crate) debug: Debug,
    pub(crate) cache: Cache,
    pub(crate) clock: Clock,
    /// The cycle count at which `service` must run.
    pub(crate) stop_at: u64,
    /// `run_until`'s deadline in cycles, and in nanoseconds (to recompute the cycles when
    /// the clock changes).
    pub(crate) deadline: u64,
    pub(crate) deadline_ns: u64,
    /// The bus's next event in cycles (`u64::MAX`: none), and in nanoseconds as the bus
    /// said it.
    pub(crate) bus_event: u64,
    pub(crate) bus_event_ns: u64,
    /// A stop decided inside an instruction (semihosting exit, breakpoint, lockup).
    pub(crate) pending_stop: Option<Stop>,
    pub(crate) reset_request: Option<ResetKind>,
    pub(crate) code_generation: u64,
    pub(crate) hooks: BTreeSet<u32>,
    /// A hook already reported at this address: execute it on the next step.
    pub(crate) hook_resume: Option<u32>,
    /// Instruction count and Rt of the last single load (for load pipelining).
    pub(crate) last_load: (u64, u8),
    pub(crate) stats: Stats,
    /// Exceptions taken, by exception number.
    pub(crate) exceptions: [u64; 256],
    pub(crate) semihost_out: Vec<u8>,
}

impl Cpu {
    /// A core in its power-on state; call [`Cpu::reset`] with the bus to load SP and PC
    /// from the vector table.
    pub fn new(cfg: Config) -> Self {
        let nvic = Nvic::new(cfg.irqs, cfg.prio_bits);
        let mut cpu = Cpu {
            cfg,
            r: [0; 16],
            sp_other: 0,
            on_psp: false,
            flags: Flags::default(),
            it: 0,
            in_it: false,
            ipsr: 0,
            thumb: true,
            primask: false,
            faultmask: false,
            basepri: 0,
            control: 0,
            s: [0; 32],
            fpscr: 0,
            fp_ready: false,
            pc: 0,
            next_pc: 0,
            refill: true,
            exclusive: false,
            event: false,
            state: RunState::Running,
            nvic,
            scb: Scb::new(),
            systick: SysTick::new(),
            mpu: Mpu::default(),
            debug: Debug::default(),
            cache: Cache::new(),
            clock: Clock::new(cfg.initial_hz),
            stop_at: 0,
            deadline: 0,
            deadline_ns: 0,
            bus_event: u64::MAX,
            bus_event_ns: u64::MAX,
            pending_stop: None,
            reset_request: None,
            code_generation: 0,
            hooks: BTreeSet::new(),
            hook_resume: None,
            last_load: (u64::MAX, 16),
            stats: Stats {
                instructions: 0,
                cycles_active: 0,
                cycles_asleep: 0,
                lowest_sp: u32::MAX,
            },
            exceptions: [0; 256],
            semihost_out: Vec::new(),
        };
        cpu.reset_core_state();
        cpu
    }

    /// The configuration the core was built with.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// Resets the core (registers, NVIC, SCB, SysTick, FPU state) and loads the initial
    /// main stack pointer and the reset vector from the vector table at address 0. The
    /// bus is not reset; virtual time and statistics carry on.
    pub fn reset<B: Bus>(&mut self, bus: &mut B) {
        self.boot(bus, 0);
    }

    /// Resets the core like [`Cpu::reset`] but starts from the vector table at
    /// `vector_table` (VTOR set to it), as a bootloader that jumps to an application
    /// leaves the core: the application's initial SP and reset vector.
    pub fn boot<B: Bus>(&mut self, bus: &mut B, vector_table: u32) {
        self.reset_core_state();
        self.scb.vtor = vector_table & 0xFFFF_FF80;
        let hz = bus.core_hz();
        if u64::from(hz) != self.clock.hz() {
            self.set_clock(hz);
        }
        self.code_generation = bus.code_generation();
        self.cache.clear();
        let now = self.clock.now_ns();
        let table = self.scb.vtor;
        let sp = bus.read(table, crate::Width::Word, now);
        let pc = bus.read(table.wrapping_add(4), crate::Width::Word, now);
        match (sp, pc) {
            (Ok(sp), Ok(pc)) => {
                self.r[13] = sp & !3;
                self.note_sp(self.r[13]);
                self.thumb = pc & 1 != 0;
                self.pc = pc & !1;
            }
            _ => {
                // A vector table that cannot be read leaves the core locked up.
                self.state = RunState::LockedUp;
            }
        }
        self.nvic.sample(bus.irq_lines());
        self.stop_at = 0;
    }

    /// The architectural reset state of everything inside the core.
    fn reset_core_state(&mut self) {
        self.r = [0; 16];
        self.r[14] = 0xFFFF_FFFF;
        self.sp_other = 0;
        self.on_psp = false;
        self.flags = Flags::default();
        self.it = 0;
        self.ipsr = 0;
        self.thumb = true;
        self.primask = false;
        self.faultmask = false;
        self.basepri = 0;
        self.control = 0;
        self.s = [0; 32];
        self.fpscr = 0;
        self.fp_ready = false;
        self.refill = true;
        self.exclusive = false;
        self.event = false;
        self.state = RunState::Running;
        self.nvic.reset();
        self.scb = Scb::new();
        self.systick = SysTick::new();
        self.mpu = Mpu::default();
        self.debug.reset_core();
        self.reset_request = None;
        self.hook_resume = None;
        self.stop_at = 0;
    }

    /// Virtual time: nanoseconds since power-on.
    pub fn now_ns(&self) -> u64 {
        self.clock.now_ns()
    }

    /// Processor cycles since power-on (executing and asleep).
    pub fn cycles(&self) -> u64 {
        self.clock.cycles
    }

    /// The statistics so far.
    pub fn stats(&self) -> Stats {
        let mut s = self.stats;
        s.cycles_active = self.clock.cycles - s.cycles_asleep;
        s
    }

    /// Exceptions taken so far, by exception number (16 + n for IRQ n).
    pub fn exceptions_taken(&self) -> &[u64; 256] {
        &self.exceptions
    }

    /// The fault status registers as the program would read them.
    pub fn fault_status(&self) -> FaultStatus {
        FaultStatus {
            cfsr: self.scb.cfsr,
            hfsr: self.scb.hfsr,
            mmfar: self.scb.mmfar,
            bfar: self.scb.bfar,
        }
    }

    /// Whether the core sleeps (WFI, WFE, sleep-on-exit).
    pub fn is_sleeping(&self) -> bool {
        matches!(self.state, RunState::SleepWfi | RunState::SleepWfe)
    }

    /// Whether the core is locked up (a fault it could not take).
    pub fn is_locked_up(&self) -> bool {
        self.state == RunState::LockedUp
    }

    /// Stop [`Cpu::run_until`] with [`Stop::Hook`] whenever the PC reaches `addr` (bit 0
    /// ignored).
    pub fn add_pc_hook(&mut self, addr: u32) {
        let addr = addr & !1;
        self.hooks.insert(addr);
        self.cache.set_hook(addr, true);
    }

    /// Removes a hook set with [`Cpu::add_pc_hook`].
    pub fn remove_pc_hook(&mut self, addr: u32) {
        let addr = addr & !1;
        self.hooks.remove(&addr);
        self.cache.set_hook(addr, false);
    }

    /// Everything the program wrote through semihosting since the last call.
    pub fn take_semihost_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.semihost_out)
    }

    /// Runs until virtual time reaches `deadline_ns` (the first instruction boundary at or
    /// after it) or something stops the core first. The bus's interrupt lines, next event,
    /// clock and code generation are read afresh on entry: whatever drove the bus between
    /// two calls is seen.
    pub fn run_until<B: Bus>(&mut self, bus: &mut B, deadline_ns: u64) -> Stop {
        // The world may have changed the bus since the last run: pick that up.
        self.deadline_ns = deadline_ns;
        self.deadline = self.clock.cycle_at(deadline_ns);
        self.after_advance(bus);
        self.stop_at = 0;
        loop {
            if self.clock.cycles >= self.stop_at {
                if let Some(stop) = self.service(bus) {
                    return stop;
                }
                continue;
            }
            if let Some(stop) = self.step(bus) {
                return stop;
            }
        }
    }

    /// Executes one instruction at `self.pc`.
    #[inline(always)]
    fn step<B: Bus>(&mut self, bus: &mut B) -> Option<Stop> {
        let pc = self.pc;
        let slot = match self.cache.get(pc) {
            Some(slot) if slot.insn != Insn::Empty => slot,
            _ => match self.decode_at(bus, pc) {
                Ok(slot) => slot,
                Err(fault) => {
                    self.raise_fault(bus, fault);
                    return None;
                }
            },
        };
        if slot.hook {
            if self.hook_resume != Some(pc) {
                self.hook_resume = Some(pc);
                return Some(Stop::Hook { pc });
            }
            self.hook_resume = None;
        }
        let mut cycles = u64::from(slot.cycles);
        if self.refill {
            self.refill = false;
            cycles += crate::cycles::refill(pc, slot.len);
            cycles += u64::from(bus.fetch_stall(pc, false));
        } else {
            cycles += u64::from(bus.fetch_stall(pc, true));
        }
        self.next_pc = pc.wrapping_add(u32::from(slot.len));
        self.r[15] = pc.wrapping_add(4);
        self.stats.instructions += 1;
        let it = self.it;
        self.in_it = it != 0;
        if it != 0 {
            self.it = crate::exec::it_advance(it);
            if !self.cond_passed(it >> 4) {
                self.clock.cycles += 1 + cycles - u64::from(slot.cycles);
                self.pc = self.next_pc;
                return None;
            }
        }
        self.clock.cycles += cycles;
        match self.exec(bus, slot.insn) {
            Ok(()) => self.pc = self.next_pc,
            Err(Trap::Fault(fault)) => {
                self.it = it;
                self.raise_fault(bus, fault);
            }
            Err(Trap::Stop(stop)) => {
                self.pc = self.next_pc;
                return Some(stop);
            }
        }
        None
    }

    /// Fetches and decodes the instruction at `pc` into the cache.
    fn decode_at<B: Bus>(&mut self, bus: &mut B, pc: u32) -> Result<Slot, Fault> {
        self.check_code_generation(bus);
        if crate::access::never_executable(pc) {
            return Err(Fault::MemInstr);
        }
        let hw1 = bus.fetch(pc).ok_or(Fault::BusInstr)?;
        let hw2 = if crate::decode::is_32bit(hw1) {
            bus.fetch(pc.wrapping_add(2)).ok_or(Fault::BusInstr)?
        } else {
            0
        };
        let (insn, len) = crate::decode::decode(hw1, hw2, pc);
        let slot = Slot {
            insn,
            len,
            cycles: crate::cycles::base(&insn),
            hook: self.hooks.contains(&pc),
        };
        self.cache.put(pc, slot);
        Ok(slot)
    }

    /// Drops decoded instructions when the bus says code changed.
    pub(crate) fn check_code_generation<B: Bus>(&mut self, bus: &mut B) {
        let generation = bus.code_generation();
        if generation != self.code_generation {
            self.code_generation = generation;
            self.cache.clear();
            for &addr in &self.hooks {
                self.cache.set_hook(addr, true);
            }
        }
    }

    /// Everything between instructions: bus events, SysTick, resets, exceptions, sleep,
    /// the deadline. Returns a stop for the caller, or `None` to go on executing.
    fn service<B: Bus>(&mut self, bus: &mut B) -> Option<Stop> {
        loop {
            if let Some(stop) = self.pending_stop.take() {
                self.recompute_stop_at();
                return Some(stop);
            }
            self.clock.rebase_if_far();
            if self.clock.cycles >= self.bus_event {
                self.advance_bus(bus);
            }
            if let Some(kind) = self.reset_request.take() {
                self.system_reset(bus, kind);
            }
            self.systick_catch_up();
            if self.state == RunState::Running && !self.thumb {
                self.raise_fault(bus, Fault::InvState);
            }
            if self.state != RunState::LockedUp {
                self.take_pending_exception(bus);
            }
            if let Some(stop) = self.pending_stop.take() {
                self.recompute_stop_at();
                return Some(stop);
            }
            if self.clock.cycles >= self.deadline {
                self.advance_bus(bus);
                self.recompute_stop_at();
                return Some(Stop::Deadline);
            }
            if self.state == RunState::Running {
                self.recompute_stop_at();
                return None;
            }
            // Asleep or locked up: jump to the next thing that can happen.
            let wake = self
                .deadline
                .min(self.bus_event)
                .min(self.systick.next_fire_cycle())
                .max(self.clock.cycles + 1);
            let slept = wake - self.clock.cycles;
            self.clock.cycles = wake;
            self.stats.cycles_asleep += slept;
        }
    }

    /// `stop_at` from the deadline, the bus's next event and SysTick.
    pub(crate) fn recompute_stop_at(&mut self) {
        self.stop_at = self
            .deadline
            .min(self.bus_event)
            .min(self.systick.next_fire_cycle())
            .min(self.clock.rebase_due());
    }

    /// Brings the bus to now and picks up what changed there.
    pub(crate) fn advance_bus<B: Bus>(&mut self, bus: &mut B) {
        bus.advance(self.clock.now_ns());
        self.after_advance(bus);
    }

    /// After the bus moved on its own: interrupt lines, resets, clock, code, next event.
    fn after_advance<B: Bus>(&mut self, bus: &mut B) {
        if let Some(cause) = bus.take_reset_request() {
            self.reset_request = Some(ResetKind::Bus(cause));
            self.stop_at = 0;
        }
        self.check_code_generation(bus);
        self.after_peripheral_access(bus, true);
    }

    /// After an access to the peripheral or device regions (or an advance): the clock, the
    /// interrupt lines and the bus's next event may have changed.
    pub(crate) fn after_peripheral_access<B: Bus>(&mut self, bus: &mut B, write: bool) {
        if write {
            let hz = bus.core_hz();
            if u64::from(hz) != self.clock.hz() {
                self.set_clock(hz);
            }
            self.check_code_generation(bus);
        }
        if self.nvic.sample(bus.irq_lines()) {
            self.new_pending();
        }
        let event_ns = bus.next_event_ns();
        if event_ns != self.bus_event_ns {
            self.bus_event_ns = event_ns;
            self.bus_event = self.clock.cycle_at(event_ns);
            self.stop_at = self.stop_at.min(self.bus_event);
        }
    }

    /// Counts at a new core clock from now: the deadline and the bus's next event move to
    /// the cycles that are now their times.
    pub(crate) fn set_clock(&mut self, hz: u32) {
        self.clock.set_hz(hz);
        self.systick.clock_changed();
        self.deadline = self.clock.cycle_at(self.deadline_ns);
        self.bus_event = self.clock.cycle_at(self.bus_event_ns);
        self.stop_at = 0;
    }

    /// AIRCR.SYSRESETREQ or a reset the bus asked for: the bus and the core reset.
    fn system_reset<B: Bus>(&mut self, bus: &mut B, kind: ResetKind) {
        match kind {
            ResetKind::Bus(cause) => bus.reset(cause),
            ResetKind::SysResetReq => bus.sysresetreq(),
        }
        if self.is_sleeping() {
            bus.sleeping(false, self.clock.now_ns());
        }
        self.reset(bus);
        self.bus_event_ns = bus.next_event_ns();
        self.bus_event = self.clock.cycle_at(self.bus_event_ns);
    }

    /// An interrupt became pending: with SCR.SEVONPEND that is a WFE wake-up event; in any
    /// case the run loop re-evaluates exceptions.
    pub(crate) fn new_pending(&mut self) {
        if self.scb.scr & SEVONPEND != 0 {
            self.event = true;
        }
        self.stop_at = 0;
    }

    /// Records an SP value for the lowest-SP statistic.
    #[inline]
    pub(crate) fn note_sp(&mut self, sp: u32) {
        if sp < self.stats.lowest_sp {
            self.stats.lowest_sp = sp;
        }
    }

    /// Puts the core to sleep (WFI/WFE/sleep-on-exit) until `service` finds a reason to
    /// wake it.
    pub(crate) fn sleep<B: Bus>(&mut self, bus: &mut B, state: RunState) {
        if self.state == RunState::Running {
            bus.sleeping(true, self.clock.now_ns());
        }
        self.state = state;
        self.stop_at = 0;
    }

    /// Wakes the core if it sleeps.
    pub(crate) fn wake<B: Bus>(&mut self, bus: &mut B) {
        if self.is_sleeping() {
            self.state = RunState::Running;
            bus.sleeping(false, self.clock.now_ns());
        }
    }
}
