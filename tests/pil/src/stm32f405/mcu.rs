//! The STM32F405 with its Cortex-M4F core running an image: m4-sim's core configured as
//! ST built it into this chip, the image loaded as a programmer would (behind a stand-in
//! for the Tau Labs bootloader's hand-over when it is linked at 0x0802_0000), embassy's
//! task polls watched to time the boot, and the co-simulation's [`Machine`] on top.

use std::fmt;

use m4_sim::{Cpu, Stop};

use super::memory::LoadError;
use super::{Config, Entry, Stm32f405, map};
use crate::wire::{Outside, Pin};
use crate::world::machine::{Halt, Machine, MachineStats};

/// Whether `symbol` is an embassy task poll (`embassy_executor::raw::TaskStorage<F>::
/// poll`, one per task in an image), in the legacy (`…TaskStorage$LT$F$GT$4poll…`) or the
/// v0 mangling (`…11TaskStorage…E4poll…`), not a local label of it.
pub fn is_task_poll(symbol: &str) -> bool {
    symbol.contains("TaskStorage") && symbol.contains("4poll") && !symbol.starts_with(".L")
}

/// The Cortex-M4F as the STM32F405 has it: 4 priority bits, 82 interrupts (RM0090 Table
/// 61), SysTick's reference HCLK/8 (RM0090 §7.2, Figure 21), bit-banding, no debugger (a
/// BKPT is a HardFault), 16 MHz HSI from reset.
pub fn core_config() -> m4_sim::Config {
    m4_sim::Config {
        prio_bits: 4,
        irqs: 82,
        systick_ref_div: Some(8),
        systick_tenms: 0,
        bitband: true,
        halt_on_bkpt: false,
        initial_hz: super::rcc::HSI_HZ,
    }
}

/// The task a poll function runs, from its symbol: the v0 mangling names the task's
/// future (`…15___imu_task_task30___imu_task_task_inner_function…` → `imu_task`); the
/// legacy mangling does not (`TaskStorage$LT$F$GT$4poll`), so `None`.
pub fn task_name(symbol: &str) -> Option<String> {
    const INNER: &str = "_inner_function";
    let end = symbol.find(INNER)?;
    // v0 spells the task's future `<n>X<m>X_inner_function` with m = len(X) + 15, X
    // preceded by a `_` separator when it begins with `_`: find the X that repeats with
    // the right length in between.
    let ident = (0..end).rev().find_map(|start| {
        let x = symbol.get(start..end)?;
        let before = symbol.get(..start)?;
        let separator = usize::from(x.starts_with('_'));
        let m = x.len() - separator + INNER.len();
        before.ends_with(&format!("{x}{m}")).then_some(x)
    })?;
    let ident = ident.trim_start_matches('_');
    // `#[embassy_executor::task] fn x()` spawns `__x_task`: one `_task` too many.
    let ident = ident
        .strip_suffix("_task_task")
        .map_or(ident.to_string(), |n| format!("{n}_task"));
    Some(ident).filter(|n| !n.is_empty())
}

/// An embassy task poll function of an image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TaskPoll {
    /// Its entry (Thumb bit cleared).
    pub entry: u32,
    /// The task, when the symbol says ([`task_name`]).
    pub name: Option<String>,
}

impl fmt::Display for TaskPoll {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.name {
            Some(n) => f.write_str(n),
            None => write!(f, "the task polled at 0x{:08x}", self.entry),
        }
    }
}

/// The image's embassy task polls, by entry.
pub fn task_polls(elf: &[u8]) -> Result<Vec<TaskPoll>, LoadError> {
    let mut polls: Vec<TaskPoll> = fw_elf::symbols(elf)
        .map_err(|e| LoadError::Elf(e.to_string()))?
        .into_iter()
        .filter(|s| is_task_poll(&s.name))
        .map(|s| TaskPoll {
            entry: s.address & !1,
            name: task_name(&s.name),
        })
        .collect();
    polls.sort_unstable_by_key(|p| p.entry);
    polls.dedup_by_key(|p| p.entry);
    Ok(polls)
}

/// A watchdog reset and the task the executor was in when it came: the last task
/// polled, when no other poll began after it (embassy runs one task at a time, so a task
/// that never returns keeps the executor — and the supervisor — from running).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WatchdogBite {
    /// When the chip reset, ns.
    pub at_ns: u64,
    /// The last task polled before it.
    pub last_polled: Option<TaskPoll>,
    /// When that poll began, ns.
    pub polled_at_ns: u64,
}

/// Why an image cannot run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum McuError {
    /// The file does not load.
    Load(LoadError),
    /// No vector table at 0x0800_0000 or 0x0802_0000.
    NoVectorTable,
}

impl fmt::Display for McuError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            McuError::Load(e) => e.fmt(f),
            McuError::NoVectorTable => {
                write!(f, "no vector table at 0x0800_0000 or 0x0802_0000")
            }
        }
    }
}

impl std::error::Error for McuError {}

impl From<LoadError> for McuError {
    fn from(e: LoadError) -> Self {
        McuError::Load(e)
    }
}

/// The chip, its core and the image's task polls.
pub struct Mcu<O: Outside> {
    cpu: Cpu,
    soc: Stm32f405<O>,
    entry: Entry,
    /// Each task poll and whether it ran since the last reset.
    polls: Vec<(TaskPoll, bool)>,
    /// The last poll: which, and when.
    last_poll: Option<(usize, u64)>,
    bites: Vec<WatchdogBite>,
    seen_watchdog_resets: u32,
    reset_at: u64,
    boot_ns: Option<u64>,
    /// When the last task was first polled since the last reset, ns since power-on.
    last_first_poll_ns: Option<u64>,
    seen_resets: u32,
    lockups: u32,
}

impl<O: Outside> Mcu<O> {
    /// The chip on `outside` with `elf` programmed, out of power-on reset.
    pub fn new(outside: O, config: Config, elf: &[u8]) -> Result<Self, McuError> {
        let mut soc = Stm32f405::new(outside, config);
        soc.load_elf(elf)?;
        let entry = soc.boot_entry().ok_or(McuError::NoVectorTable)?;
        if entry.vector_table != map::FLASH_BASE {
            soc.install_bootloader_handover(entry.vector_table)?;
        }
        let polls = task_polls(elf)?;
        let mut cpu = Cpu::new(core_config());
        cpu.reset(&mut soc);
        for p in &polls {
            cpu.add_pc_hook(p.entry);
        }
        Ok(Self {
            cpu,
            soc,
            entry,
            polls: polls.into_iter().map(|p| (p, false)).collect(),
            last_poll: None,
            bites: Vec::new(),
            seen_watchdog_resets: 0,
            reset_at: 0,
            boot_ns: None,
            last_first_poll_ns: None,
            seen_resets: 0,
            lockups: 0,
        })
    }

    /// The chip.
    pub fn soc(&self) -> &Stm32f405<O> {
        &self.soc
    }

    /// The chip, mutably (inputs, the USB host, faults to inject).
    pub fn soc_mut(&mut self) -> &mut Stm32f405<O> {
        &mut self.soc
    }

    /// The core.
    pub fn cpu(&self) -> &Cpu {
        &self.cpu
    }

    /// Where the image starts.
    pub fn entry(&self) -> Entry {
        self.entry
    }

    /// How many tasks the image has, and how many ran since the last reset.
    pub fn tasks_polled(&self) -> (usize, usize) {
        let ran = self.polls.iter().filter(|(_, r)| *r).count();
        (self.polls.len(), ran)
    }

    /// Time from the last reset until every task had been polled.
    pub fn boot_ns(&self) -> Option<u64> {
        self.boot_ns
    }

    /// The image's tasks (their poll functions).
    pub fn tasks(&self) -> impl Iterator<Item = &TaskPoll> {
        self.polls.iter().map(|(p, _)| p)
    }

    /// The watchdog resets so far, each with the task the executor was in.
    pub fn watchdog_bites(&self) -> &[WatchdogBite] {
        &self.bites
    }

    fn polled(&mut self, pc: u32) {
        if let Some(i) = self.polls.iter().position(|(p, _)| p.entry == pc) {
            if let Some(p) = self.polls.get_mut(i)
                && !p.1
            {
                p.1 = true;
                self.last_first_poll_ns = Some(self.cpu.now_ns());
            }
            self.last_poll = Some((i, self.cpu.now_ns()));
        }
        if self.boot_ns.is_none() && !self.polls.is_empty() && self.polls.iter().all(|p| p.1) {
            self.boot_ns = Some(self.cpu.now_ns().saturating_sub(self.reset_at));
        }
    }

    fn note_resets(&mut self) {
        if self.soc.watchdog_resets() != self.seen_watchdog_resets {
            self.seen_watchdog_resets = self.soc.watchdog_resets();
            let last = self.last_poll;
            self.bites.push(WatchdogBite {
                at_ns: self.soc.now_ns(),
                last_polled: last
                    .and_then(|(i, _)| self.polls.get(i))
                    .map(|(p, _)| p.clone()),
                polled_at_ns: last.map_or(0, |(_, t)| t),
            });
        }
        if self.soc.resets() != self.seen_resets {
            self.seen_resets = self.soc.resets();
            self.last_poll = None;
            self.reset_at = self.soc.now_ns();
            self.boot_ns = None;
            self.last_first_poll_ns = None;
            for p in &mut self.polls {
                p.1 = false;
            }
        }
    }
}

impl<O: Outside> Machine for Mcu<O> {
    type Board = O;

    fn board(&mut self) -> &mut O {
        self.soc.outside_mut()
    }

    fn now_ns(&self) -> u64 {
        self.cpu.now_ns()
    }

    fn run_until(&mut self, deadline_ns: u64) -> Result<(), Halt> {
        loop {
            let stop = self.cpu.run_until(&mut self.soc, deadline_ns);
            self.note_resets();
            match stop {
                Stop::Deadline => return Ok(()),
                Stop::Hook { pc } => self.polled(pc),
                // Locked up: time passes until a reset (the watchdog's, a power cycle).
                Stop::Lockup { .. } => {
                    if self.soc.powered() {
                        self.lockups += 1;
                    }
                }
                Stop::Exit { code } => {
                    return Err(Halt::Error(format!(
                        "the image exited through semihosting ({code})"
                    )));
                }
                Stop::Breakpoint { pc, imm } => {
                    return Err(Halt::Error(format!("BKPT #{imm} at 0x{pc:08x}")));
                }
            }
        }
    }

    fn drive_input(&mut self, pin: Pin, level: bool, at_ns: u64) {
        self.soc.drive_input(pin, level, at_ns);
    }

    fn uart_receive(&mut self, uart: u8, byte: u8, at_ns: u64) {
        self.soc.uart_receive(uart, byte, at_ns);
    }

    fn uart_baud(&mut self, uart: u8) -> Option<u32> {
        Some(self.soc.uart_baud(uart)).filter(|&b| b > 0)
    }

    fn set_powered(&mut self, on: bool, _now_ns: u64) {
        self.soc.set_powered(on);
    }

    fn powered(&self) -> bool {
        self.soc.powered()
    }

    fn stats(&self) -> MachineStats {
        let cpu = self.cpu.stats();
        let time = self.soc.cpu_time();
        MachineStats {
            instructions: cpu.instructions,
            active_ns: time.busy_ns,
            asleep_ns: time.asleep_ns,
            stack_top: self.entry.initial_sp,
            lowest_sp: (cpu.lowest_sp != u32::MAX).then_some(cpu.lowest_sp),
            watchdog_resets: self.soc.watchdog_resets(),
            resets: self.soc.resets(),
            boot_ns: self.boot_ns,
            tasks_polled: u32::try_from(self.polls.iter().filter(|p| p.1).count())
                .unwrap_or(u32::MAX),
            tasks_total: u32::try_from(self.polls.len()).unwrap_or(u32::MAX),
            last_first_poll_ns: self.last_first_poll_ns,
            lockups: self.lockups,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn task_polls_are_found_in_both_manglings() {
        assert!(is_task_poll(
            "_ZN16embassy_executor3raw20TaskStorage$LT$F$GT$4poll17hb29a26927235efbdE"
        ));
        assert!(is_task_poll(
            "_RNvMs1_NtCs5APViPlMGpI_16embassy_executor3rawINtB5_11TaskStorageNCNvNvNtNtNtCsve3zSKosp0_9flight_fw8firmware5tasks3imu15___imu_task_task30___imu_task_task_inner_function0E4pollB1c_"
        ));
        assert!(!is_task_poll(
            ".Lswitch.table._ZN16embassy_executor3raw20TaskStorage$LT$F$GT$4poll17hb29a26927235efbdE.1084"
        ));
        assert!(!is_task_poll(
            "_ZN16embassy_executor3raw8Executor4poll17h0E"
        ));
    }

    #[test]
    fn task_names_come_from_the_v0_mangling() {
        assert_eq!(
            task_name(
                "_RNvMs1_NtCs5APViPlMGpI_16embassy_executor3rawINtB5_11TaskStorageNCNvNvNtNtNtCsve3zSKosp0_9flight_fw8firmware5tasks3imu15___imu_task_task30___imu_task_task_inner_function0E4pollB1c_"
            )
            .as_deref(),
            Some("imu_task")
        );
        assert_eq!(
            task_name(
                "_RNvMs1_NtCs5APViPlMGpI_16embassy_executor3rawINtB5_11TaskStorageNCNvNvNtCsve3zSKosp0_9flight_fw8firmware21_____embassy_main_task36_____embassy_main_task_inner_function0E4pollB18_"
            )
            .as_deref(),
            Some("embassy_main_task")
        );
        assert_eq!(
            task_name("_ZN16embassy_executor3raw20TaskStorage$LT$F$GT$4poll17hb29a26927235efbdE"),
            None
        );
    }
}
