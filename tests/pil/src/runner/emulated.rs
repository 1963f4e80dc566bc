//! The emulated MCUs the `pil` binary flies: this crate's STM32F405 and nRF52840 models,
//! each the `m4_sim::Bus` of one `m4_sim::Cpu`, as [`Machine`]s.
//!
//! Around each core the runner watches what a debugger would: the entry of every embassy
//! task poll (`TaskStorage<F>::poll`, one PC hook per task, dropped once hit, so the hooks
//! cost nothing after boot) for `boot_ms`; the resets the core takes and why (a tap on the
//! bus's `reset` call); the time the core sleeps (the bus's `sleeping` call) for the CPU
//! load; the lowest stack pointer (the core's own statistic).

use std::collections::BTreeSet;

use m4_sim::{Bus, BusFault, Config as CpuConfig, Cpu, ResetCause, Stop, Width};

use super::image::Image;
use super::{MODULE_DEVICE_ID, Platform};
use crate::board::flight::FlightBoard;
use crate::board::module::ModuleBoard;
use crate::nrf52840::Nrf52840;
use crate::stm32f405::Stm32f405;
use crate::wire::Pin;
use crate::world::machine::{Halt, Injection, Machine, MachineStats};

/// What the tap saw of the bus's resets and sleep.
#[derive(Debug, Clone, Copy, Default)]
struct Log {
    watchdog: u32,
    resets: u32,
    last_reset_ns: u64,
    reset_seen: bool,
    asleep_since: Option<u64>,
    asleep_ns: u64,
}

/// The bus as the core sees it, with the runner listening to `reset` and `sleeping`.
struct Tap<'a, B: Bus> {
    bus: &'a mut B,
    log: &'a mut Log,
    now_ns: u64,
}

impl<B: Bus> Bus for Tap<'_, B> {
    fn fetch(&mut self, addr: u32) -> Option<u16> {
        self.bus.fetch(addr)
    }
    fn fetch_stall(&mut self, addr: u32, sequential: bool) -> u32 {
        self.bus.fetch_stall(addr, sequential)
    }
    fn read(&mut self, addr: u32, width: Width, now_ns: u64) -> Result<u32, BusFault> {
        self.now_ns = now_ns;
        self.bus.read(addr, width, now_ns)
    }
    fn write(&mut self, addr: u32, width: Width, value: u32, now_ns: u64) -> Result<(), BusFault> {
        self.now_ns = now_ns;
        self.bus.write(addr, width, value, now_ns)
    }
    fn access_stall(&mut self, addr: u32, write: bool) -> u32 {
        self.bus.access_stall(addr, write)
    }
    fn code_generation(&self) -> u64 {
        self.bus.code_generation()
    }
    fn irq_lines(&self) -> [u32; 8] {
        self.bus.irq_lines()
    }
    fn next_event_ns(&self) -> u64 {
        self.bus.next_event_ns()
    }
    fn advance(&mut self, now_ns: u64) {
        self.now_ns = now_ns;
        self.bus.advance(now_ns);
    }
    fn core_hz(&self) -> u32 {
        self.bus.core_hz()
    }
    fn take_reset_request(&mut self) -> Option<ResetCause> {
        self.bus.take_reset_request()
    }
    fn reset(&mut self, cause: ResetCause) {
        self.log.resets += 1;
        if cause == ResetCause::Watchdog {
            self.log.watchdog += 1;
        }
        self.log.last_reset_ns = self.now_ns;
        self.log.reset_seen = true;
        self.bus.reset(cause);
    }
    fn sleeping(&mut self, asleep: bool, now_ns: u64) {
        self.now_ns = now_ns;
        match (asleep, self.log.asleep_since) {
            (true, None) => self.log.asleep_since = Some(now_ns),
            (false, Some(s)) => {
                self.log.asleep_ns += now_ns.saturating_sub(s);
                self.log.asleep_since = None;
            }
            _ => {}
        }
        self.bus.sleeping(asleep, now_ns);
    }
}

/// One core on its SoC model, with the runner's watch.
pub struct Emulated<B: Bus> {
    cpu: Cpu,
    soc: B,
    log: Log,
    polls: Vec<u32>,
    polled: BTreeSet<u32>,
    boot_from_ns: u64,
    last_first_poll_ns: Option<u64>,
    stack_top: u32,
    locked: bool,
    lockups: u32,
    powered: bool,
}

impl<B: Bus> Emulated<B> {
    fn new(config: CpuConfig, mut soc: B, image: &Image) -> Self {
        let mut cpu = Cpu::new(config);
        let mut log = Log::default();
        cpu.reset(&mut Tap {
            bus: &mut soc,
            log: &mut log,
            now_ns: 0,
        });
        for &p in &image.task_polls {
            cpu.add_pc_hook(p);
        }
        Self {
            cpu,
            soc,
            log,
            polls: image.task_polls.clone(),
            polled: BTreeSet::new(),
            boot_from_ns: 0,
            last_first_poll_ns: None,
            stack_top: image.stack_top,
            locked: false,
            lockups: 0,
            powered: true,
        }
    }

    fn run(&mut self, deadline_ns: u64) -> Result<(), Halt> {
        if !self.powered {
            return Ok(());
        }
        loop {
            let stop = self.cpu.run_until(
                &mut Tap {
                    bus: &mut self.soc,
                    log: &mut self.log,
                    now_ns: 0,
                },
                deadline_ns,
            );
            if std::mem::take(&mut self.log.reset_seen) {
                self.locked = false;
            }
            match stop {
                Stop::Deadline => return Ok(()),
                Stop::Hook { pc } => {
                    self.cpu.remove_pc_hook(pc);
                    if self.polled.insert(pc) {
                        self.last_first_poll_ns = Some(self.cpu.now_ns());
                    }
                }
                Stop::Lockup { .. } => {
                    if !self.locked {
                        self.locked = true;
                        self.lockups += 1;
                    }
                    if self.cpu.now_ns() >= deadline_ns {
                        return Ok(());
                    }
                }
                Stop::Exit { code } => return Err(Halt::Error(format!("semihosting exit {code}"))),
                Stop::Breakpoint { pc, imm } => {
                    return Err(Halt::Error(format!("BKPT #{imm} at 0x{pc:08X}")));
                }
            }
        }
    }

    /// The core (registers, for a debugger's look).
    pub fn cpu(&self) -> &Cpu {
        &self.cpu
    }

    /// The SoC model.
    pub fn soc(&self) -> &B {
        &self.soc
    }

    /// Task polls reached since power-on, of how many.
    pub fn tasks_polled(&self) -> (usize, usize) {
        (self.polled.len(), self.polls.len())
    }

    fn stats(&self) -> MachineStats {
        let s = self.cpu.stats();
        let now = self.cpu.now_ns();
        let asleep =
            self.log.asleep_ns + self.log.asleep_since.map_or(0, |t| now.saturating_sub(t));
        MachineStats {
            instructions: s.instructions,
            active_ns: now.saturating_sub(asleep),
            asleep_ns: asleep,
            stack_top: self.stack_top,
            lowest_sp: (s.lowest_sp != u32::MAX).then_some(s.lowest_sp),
            watchdog_resets: self.log.watchdog,
            resets: self.log.resets,
            boot_ns: self
                .last_first_poll_ns
                .map(|t| t.saturating_sub(self.boot_from_ns)),
            tasks_polled: u32::try_from(self.polled.len()).unwrap_or(u32::MAX),
            tasks_total: u32::try_from(self.polls.len()).unwrap_or(u32::MAX),
            last_first_poll_ns: self.last_first_poll_ns,
            lockups: self.lockups,
        }
    }
}

/// The STM32F405's core: 4 priority bits, 82 interrupts (RM0090 table 61), SysTick's
/// external reference HCLK/8, bit-banding, no debugger (BKPT faults), 16 MHz HSI at reset.
pub fn stm32f405_core() -> CpuConfig {
    CpuConfig {
        prio_bits: 4,
        irqs: 82,
        systick_ref_div: Some(8),
        systick_tenms: 0,
        bitband: true,
        halt_on_bkpt: false,
        initial_hz: 16_000_000,
    }
}

/// The nRF52840's core: 3 priority bits, 48 interrupts (PS "Instantiation"), no SysTick
/// reference, no bit-banding, no debugger, 64 MHz.
pub fn nrf52840_core() -> CpuConfig {
    CpuConfig {
        prio_bits: 3,
        irqs: 48,
        systick_ref_div: None,
        systick_tenms: 0,
        bitband: false,
        halt_on_bkpt: false,
        initial_hz: crate::nrf52840::map::CORE_HZ,
    }
}

/// The flight MCU.
pub type FlightMcu = Emulated<Stm32f405<FlightBoard>>;
/// The module MCU.
pub type ModuleMcu = Emulated<Nrf52840<ModuleBoard>>;

impl Machine for FlightMcu {
    type Board = FlightBoard;

    fn board(&mut self) -> &mut FlightBoard {
        self.soc.outside_mut()
    }
    fn now_ns(&self) -> u64 {
        self.cpu.now_ns()
    }
    fn run_until(&mut self, deadline_ns: u64) -> Result<(), Halt> {
        self.run(deadline_ns)
    }
    fn drive_input(&mut self, pin: Pin, level: bool, at_ns: u64) {
        self.soc.drive_input(pin, level, at_ns);
    }
    fn uart_receive(&mut self, uart: u8, byte: u8, at_ns: u64) {
        self.soc.uart_receive(uart, byte, at_ns);
    }
    fn uart_baud(&mut self, uart: u8) -> Option<u32> {
        Some(self.soc.uart_baud(uart)).filter(|b| *b > 0)
    }
    fn usb_plug(&mut self, plugged: bool) -> bool {
        self.soc.usb_plug(plugged);
        true
    }
    fn usb_type(&mut self, line: &[u8]) -> usize {
        self.soc.usb_send(line);
        self.soc.usb_take_received().len()
    }
    fn set_powered(&mut self, on: bool, now_ns: u64) {
        if on && !self.powered {
            self.soc
                .request_reset(crate::stm32f405::rcc::ResetKind::PowerOn);
            self.boot_from_ns = now_ns;
        }
        if !on {
            self.soc.outside_mut().power_off(now_ns);
        }
        self.powered = on;
    }
    fn powered(&self) -> bool {
        self.powered
    }
    fn stats(&self) -> MachineStats {
        self.stats()
    }
    fn inject(&mut self, injection: Injection) -> bool {
        match injection {
            Injection::DmaTransferError { controller, stream } => {
                let Some(dma) = usize::from(controller)
                    .checked_sub(1)
                    .and_then(|c| self.soc.dma.get_mut(c))
                else {
                    return false;
                };
                dma.complete(
                    usize::from(stream),
                    crate::stm32f405::dma::Outcome::BusError,
                );
                let now = self.soc.now_ns();
                self.soc.refresh(now);
                true
            }
        }
    }
    fn read_memory(&self, addr: u32, len: usize) -> Option<Vec<u8>> {
        let (base, mem) = if addr >= crate::stm32f405::map::SRAM_BASE {
            (crate::stm32f405::map::SRAM_BASE, self.soc.sram_contents())
        } else {
            (crate::stm32f405::map::FLASH_BASE, self.soc.flash_contents())
        };
        let off = addr.checked_sub(base)? as usize;
        mem.get(off..off + len).map(<[u8]>::to_vec)
    }
}

impl Machine for ModuleMcu {
    type Board = ModuleBoard;

    fn board(&mut self) -> &mut ModuleBoard {
        self.soc.outside_mut()
    }
    fn now_ns(&self) -> u64 {
        self.cpu.now_ns()
    }
    fn run_until(&mut self, deadline_ns: u64) -> Result<(), Halt> {
        self.run(deadline_ns)
    }
    fn drive_input(&mut self, pin: Pin, level: bool, at_ns: u64) {
        self.soc.drive_input(pin, level, at_ns);
    }
    fn uart_receive(&mut self, uart: u8, byte: u8, at_ns: u64) {
        self.soc.uart_receive(uart, byte, at_ns);
    }
    fn uart_baud(&mut self, uart: u8) -> Option<u32> {
        // The configured rate, transmitting or receiving.
        let reg = self.soc.uarte_baudrate(uart)?;
        crate::nrf52840::uarte_bit_ps(reg).map(|ps| (1e12 / ps as f64).round() as u32)
    }
    fn set_powered(&mut self, on: bool, _now_ns: u64) {
        self.powered = on;
    }
    fn powered(&self) -> bool {
        self.powered
    }
    fn stats(&self) -> MachineStats {
        self.stats()
    }
}

const FLASH_BASE: u32 = crate::stm32f405::map::FLASH_BASE;

/// A stand-in for the Tau Labs bootloader's hand-off, for sector 0: a vector table (the
/// application's stack, reset at 0x0800_0009) and five Thumb instructions that load the
/// application's table at `app`, set MSP from its word 0 and branch to its word 1:
/// `ldr r0, =app; ldr r1, [r0]; mov sp, r1; ldr r1, [r0, #4]; bx r1`.
pub fn bootloader_stand_in(app: u32, stack: u32) -> Vec<u8> {
    let mut code: Vec<u8> = [stack, FLASH_BASE + 0x9]
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .collect();
    for half in [0x4802u16, 0x6801, 0x468D, 0x6841, 0x4708, 0xBF00] {
        code.extend(half.to_le_bytes());
    }
    code.extend(app.to_le_bytes());
    code
}

/// The machines of the images on this crate's SoC models.
#[derive(Debug, Clone, Copy, Default)]
pub struct EmulatedBoards;

impl Platform for EmulatedBoards {
    type Flight = FlightMcu;
    type Module = ModuleMcu;

    fn flight(
        &self,
        image: &Image,
        board: FlightBoard,
        settings: &(u32, Vec<u8>),
        lsi_hz: Option<f64>,
        seed: u64,
    ) -> Result<FlightMcu, String> {
        let mut config = crate::stm32f405::Config {
            seed,
            ..crate::stm32f405::Config::default()
        };
        if let Some(hz) = lsi_hz {
            config.lsi_hz = hz.round() as u32;
        }
        let mut soc = Stm32f405::new(board, config);
        soc.load_elf(&image.bytes)
            .map_err(|e| format!("{}: {e}", image.path.display()))?;
        // Linked behind the Tau Labs bootloader: its hand-off (MSP and PC from the
        // application's table) in sector 0.
        if let Some(&(app, _)) = image.segments.first().filter(|(a, _)| *a != FLASH_BASE) {
            soc.program_flash(FLASH_BASE, &bootloader_stand_in(app, image.stack_top))
                .map_err(|e| format!("bootloader stand-in: {e}"))?;
        }
        soc.program_flash(settings.0, &settings.1)
            .map_err(|e| format!("settings flash: {e}"))?;
        Ok(Emulated::new(stm32f405_core(), soc, image))
    }

    fn module(
        &self,
        image: &Image,
        board: ModuleBoard,
        settings: &(u32, Vec<u8>),
        seed: u64,
    ) -> Result<ModuleMcu, String> {
        let config = crate::nrf52840::Config {
            device_id: MODULE_DEVICE_ID,
            rng_seed: seed,
            ..crate::nrf52840::Config::default()
        };
        let mut soc = Nrf52840::new(board, config);
        soc.load_elf(&image.bytes)
            .map_err(|e| format!("{}: {e}", image.path.display()))?;
        // Linked behind the MBR and the UF2 bootloader: their stand-ins hand over to it.
        if let Some(&(app, _)) = image.segments.first().filter(|(a, _)| *a != 0) {
            soc.install_uf2_boot_chain(app);
        }
        soc.load_segment(settings.0, &settings.1)
            .map_err(|e| format!("settings flash: {e}"))?;
        Ok(Emulated::new(nrf52840_core(), soc, image))
    }
}
