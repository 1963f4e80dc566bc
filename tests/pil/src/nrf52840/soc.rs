//! The chip: memories, peripherals and the board, behind `m4_sim::Bus`. It decodes each
//! access, keeps every peripheral on virtual time (events happen at their own instants,
//! in order, each routed through the PPI at once), re-reads the inputs the image watches
//! after anything that may have changed them, and records what it does not model.
//!
//! The CPU's own memory accesses (RAM, flash) change neither the peripherals nor the
//! inputs, and they are most of its accesses: the chip remembers its next event and
//! whether its inputs are settled until something else happens ([`Quiet`]), so such an
//! access costs no scan of the peripherals and no re-read of the pins, and the core's
//! look at the interrupt lines after it none either. This assumes, as
//! the boards do, that `Outside::pin_level` answers the same until the board is changed
//! (through [`Nrf52840::outside_mut`] or the chip's own calls to it).

use std::cell::Cell;

use m4_sim::bus::ResetCause;
use m4_sim::{Bus, BusFault, Width};

use super::boot;
use super::clock::{ClockFaults, LfTiming, Supply, resetreas};
use super::events::Ctx;
use super::ficr::{Ficr, Variant};
use super::gpio::Pins;
use super::map::{
    CODE_RAM_BASE, CORE_HZ, FICR_BASE, FLASH_SIZE, GPIO_BASE, GPIO_END, INFO_PAGE_SIZE,
    PERIPH_BASE, PERIPH_END, RAM_BASE, RAM_SIZE, UICR_BASE, base, slot,
};
use super::memory::{Anomaly198, Anomaly198Mode, Flash, Ram, Uicr, regout0_volts, uicr};
use super::nvmc::FlashTiming;
use super::parts::Parts;
use super::records::{Records, Unmodelled};
use crate::wire::{Outside, Pin};

/// How the chip is built and wired, and the faults to inject.
#[derive(Clone, Debug)]
pub struct Config {
    /// Build code (FICR.INFO.VARIANT).
    pub variant: Variant,
    /// FICR.DEVICEID.
    pub device_id: u64,
    /// The supply mode; the module's nice!nano is VDDH-supplied.
    pub supply: Supply,
    /// Crystals that never start.
    pub clock_faults: ClockFaults,
    /// The 32.768 kHz clock's frequency error, ppm (positive = fast).
    pub lf_ppm: f64,
    /// Seed of the RNG peripheral's bytes.
    pub rng_seed: u64,
    /// Anomaly 198: detect only, or also corrupt.
    pub anomaly_198: Anomaly198Mode,
    /// Instruction-fetch timing from flash.
    pub flash_timing: FlashTiming,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            variant: Variant::default(),
            device_id: 0x5EED_0F0F_1234_5678,
            supply: Supply::Vddh { volts: 5.0 },
            clock_faults: ClockFaults::default(),
            lf_ppm: 0.0,
            rng_seed: 0,
            anomaly_198: Anomaly198Mode::Detect,
            flash_timing: FlashTiming::default(),
        }
    }
}

/// Why an image could not be loaded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LoadError {
    /// Not a usable ELF file.
    Elf(fw_elf::ElfError),
    /// A segment outside flash and UICR.
    Outside {
        /// Its load address.
        addr: u32,
        /// Its length.
        len: usize,
    },
}

impl core::fmt::Display for LoadError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LoadError::Elf(e) => write!(f, "{e}"),
            LoadError::Outside { addr, len } => {
                write!(
                    f,
                    "segment at 0x{addr:08X} ({len} bytes) is neither flash nor UICR"
                )
            }
        }
    }
}

impl std::error::Error for LoadError {}

/// A reset the chip went through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResetRecord {
    /// When, ns.
    pub at_ns: u64,
    /// Why.
    pub cause: ResetCause,
}

/// Peripheral IDs that exist on the nRF52840 (an access there is unmodelled, not a fault).
const fn peripheral_exists(id: u32) -> bool {
    id <= 0x29 || id == 0x2D || id == 0x2F
}

/// What stays true while only the CPU's memory accesses (and the reset poll) happen; forgotten
/// ([`Nrf52840::changed`]) at anything else.
#[derive(Debug, Default)]
struct Quiet {
    /// The next internal event (peripherals and queued inputs) as last computed.
    next_event: Cell<Option<u64>>,
    /// The peripherals' interrupt lines as last computed.
    irq_lines: Cell<Option<[u32; 8]>>,
    /// The inputs were settled and no event waits for routing: settling them again would
    /// find nothing.
    settled: bool,
}

/// The nRF52840 around a board `O`.
pub struct Nrf52840<O: Outside> {
    outside: O,
    config: Config,
    parts: Parts,
    flash: Flash,
    uicr: Uicr,
    ficr: Ficr,
    ram: Ram,
    pins: Pins,
    records: Records,
    fired: Vec<u32>,
    now: u64,
    flash_generation: u64,
    gpio_volts: f32,
    lf_seen: Option<LfTiming>,
    stall_reported_until: u64,
    asleep_since: Option<u64>,
    sleep_ns: u64,
    resets: Vec<ResetRecord>,
    quiet: Quiet,
}

impl<O: Outside> Nrf52840<O> {
    /// A powered-up chip with erased flash and UICR on board `outside`.
    pub fn new(outside: O, config: Config) -> Self {
        let parts = Parts::new(
            config.clock_faults,
            config.supply,
            config.lf_ppm,
            config.flash_timing,
            config.rng_seed,
            config.anomaly_198 == Anomaly198Mode::Corrupt,
        );
        let mut chip = Self {
            outside,
            ficr: Ficr::new(config.variant, config.device_id),
            config,
            parts,
            flash: Flash::new(),
            uicr: Uicr::new(),
            ram: Ram::new(),
            pins: Pins::new(),
            records: Records::default(),
            fired: Vec::new(),
            now: 0,
            flash_generation: 0,
            gpio_volts: 0.0,
            lf_seen: None,
            stall_reported_until: 0,
            asleep_since: None,
            sleep_ns: 0,
            resets: Vec::new(),
            quiet: Quiet::default(),
        };
        chip.latch_uicr();
        chip
    }

    /// What the chip reads from UICR at reset: the REG0 output (the GPIO level on a
    /// VDDH-supplied board) and whether P0.09/P0.10 are NFC pads.
    fn latch_uicr(&mut self) {
        self.gpio_volts = match self.config.supply {
            Supply::Vddh { .. } => regout0_volts(self.uicr.word(uicr::REGOUT0)),
            Supply::Vdd { volts } => volts,
        };
        let vddh = match self.config.supply {
            Supply::Vddh { volts } => volts,
            Supply::Vdd { volts } => volts,
        };
        self.parts.saadc.supplies = (self.gpio_volts, vddh);
        self.pins.nfc_pads = self.uicr.word(uicr::NFCPINS) & 1 != 0;
    }

    /// Programs a load segment as a debug probe would (before the chip powers up: UICR
    /// effects apply at once).
    pub fn load_segment(&mut self, addr: u32, data: &[u8]) -> Result<(), LoadError> {
        self.changed();
        let outside = LoadError::Outside {
            addr,
            len: data.len(),
        };
        if addr >= UICR_BASE
            && (addr as u64 + data.len() as u64) <= (UICR_BASE + INFO_PAGE_SIZE) as u64
        {
            for (i, chunk) in data.chunks(4).enumerate() {
                let mut word = [0xFF; 4];
                for (w, b) in word.iter_mut().zip(chunk) {
                    *w = *b;
                }
                self.uicr
                    .program(addr - UICR_BASE + 4 * i as u32, u32::from_le_bytes(word));
            }
            self.latch_uicr();
            return Ok(());
        }
        if !self.flash.load(addr, data) {
            return Err(outside);
        }
        self.flash_generation += 1;
        Ok(())
    }

    /// Programs every loadable segment of an ELF image; returns the bytes programmed.
    pub fn load_elf(&mut self, elf: &[u8]) -> Result<usize, LoadError> {
        let segments = fw_elf::load_segments(elf).map_err(LoadError::Elf)?;
        let mut bytes = 0;
        for s in &segments {
            self.load_segment(s.address, &s.data)?;
            bytes += s.data.len();
        }
        Ok(bytes)
    }

    /// Installs the MBR and UF2-bootloader stand-ins (`boot`) for an application at `app`,
    /// with the UICR words the bootloader leaves.
    pub fn install_uf2_boot_chain(&mut self, app: u32) {
        self.changed();
        for (addr, bytes) in boot::flash_segments(app) {
            self.flash.load(addr, &bytes);
        }
        for (offset, value) in boot::UICR_WORDS {
            self.uicr.program(offset, value);
        }
        self.flash_generation += 1;
        self.latch_uicr();
    }

    /// Programs a UICR word as a debug probe would (effective from the next reset, or now
    /// if the chip has not run yet).
    pub fn program_uicr(&mut self, offset: u32, value: u32) {
        self.changed();
        self.uicr.program(offset, value);
        if self.now == 0 {
            self.latch_uicr();
        }
    }

    /// A UICR word.
    pub fn uicr_word(&self, offset: u32) -> u32 {
        self.uicr.word(offset)
    }

    /// The GPIO supply (VDD) since the last reset, V: REGOUT0's output on a VDDH board.
    /// A board refuses to talk to 3.3 V chips when this is far below their levels.
    pub const fn gpio_supply_volts(&self) -> f32 {
        self.gpio_volts
    }

    /// The board queues a level on an input pin from `at_ns` on (see `gpio` for how it
    /// combines with `Outside::pin_level`).
    pub fn drive_input(&mut self, pin: Pin, level: bool, at_ns: u64) {
        self.changed();
        self.pins.drive_input(pin, level, at_ns);
    }

    /// The board queues a byte on UARTE `uart` (1 = UARTE0, 2 = UARTE1, as in
    /// `Outside::uart_sent`) whose stop bit ends at `at_ns`.
    pub fn uart_receive(&mut self, uart: u8, byte: u8, at_ns: u64) {
        self.queue_uart(uart, byte, None, at_ns);
    }

    /// As [`Self::uart_receive`], for a byte sent at `baud`: the receiver samples it at its
    /// own rate, so a rate far enough off changes it or makes a framing error.
    pub fn uart_receive_at_baud(&mut self, uart: u8, byte: u8, baud: f64, at_ns: u64) {
        self.queue_uart(uart, byte, Some(baud), at_ns);
    }

    fn queue_uart(&mut self, uart: u8, byte: u8, baud: Option<f64>, at_ns: u64) {
        self.changed();
        if let Some(u) = usize::from(uart)
            .checked_sub(1)
            .and_then(|n| self.parts.uarte.get_mut(n))
        {
            u.receive(byte, baud, at_ns);
        }
    }

    /// The baud rate UARTE `uart` receives at now (`None` unless its receiver runs); the
    /// board sends at its own rate and can tell a mismatch.
    pub fn uart_rx_baud(&self, uart: u8) -> Option<f64> {
        usize::from(uart)
            .checked_sub(1)
            .and_then(|n| self.parts.uarte.get(n))
            .and_then(|u| u.rx_baud())
    }

    /// UARTE `uart`'s (1 = UARTE0, 2 = UARTE1) BAUDRATE register as a read would find it
    /// now, without the access (which counts as a change of the chip).
    pub fn uarte_baudrate(&mut self, uart: u8) -> Option<u32> {
        self.catch_up(self.now);
        usize::from(uart)
            .checked_sub(1)
            .and_then(|n| self.parts.uarte.get(n))
            .map(super::uarte::Uarte::baudrate)
    }

    /// The board.
    pub const fn outside(&self) -> &O {
        &self.outside
    }

    /// The board, mutably.
    pub fn outside_mut(&mut self) -> &mut O {
        // The board's levels may change; its events are the chip's own.
        self.quiet.settled = false;
        &mut self.outside
    }

    /// Accesses the model does not implement (a `boot` run should leave none).
    pub fn unmodelled(&self) -> &[Unmodelled] {
        self.records.unmodelled_accesses()
    }

    /// Everything recorded: unmodelled accesses, DMA faults, notes.
    pub const fn records(&self) -> &Records {
        &self.records
    }

    /// What the run saw of anomaly 198.
    pub const fn anomaly_198(&self) -> &Anomaly198 {
        &self.ram.anomaly
    }

    /// Flash content.
    pub fn flash(&self) -> &[u8] {
        self.flash.bytes()
    }

    /// RAM content.
    pub fn ram(&self) -> &[u8] {
        self.ram.bytes()
    }

    /// POWER.RESETREAS now.
    pub const fn reset_reason(&self) -> u32 {
        self.parts.clock.reset_reason()
    }

    /// Whether the 64 MHz crystal runs.
    pub const fn hfxo_running(&self) -> bool {
        self.parts.clock.hfxo_running()
    }

    /// Watchdog expiries since power-on.
    pub const fn watchdog_timeouts(&self) -> u64 {
        self.parts.wdt.timeouts
    }

    /// The resets the chip went through.
    pub fn resets(&self) -> &[ResetRecord] {
        &self.resets
    }

    /// Virtual time the chip has reached, ns.
    pub const fn now_ns(&self) -> u64 {
        self.now
    }

    /// Time the CPU spent asleep (WFI/WFE), ns.
    pub fn sleep_ns(&self) -> u64 {
        self.sleep_ns + self.asleep_since.map_or(0, |t| self.now.saturating_sub(t))
    }

    /// Reads of inputs nothing drove and no pull held.
    pub const fn floating_reads(&self) -> u64 {
        self.pins.floating_reads
    }

    /// Runs `f` on the peripherals with the rest of the chip lent to them at `now`.
    fn with_parts<R>(&mut self, now: u64, f: impl FnOnce(&mut Parts, &mut Ctx<'_>) -> R) -> R {
        self.changed();
        let mut ctx = Ctx {
            now,
            outside: &mut self.outside,
            ram: &mut self.ram,
            pins: &mut self.pins,
            fired: &mut self.fired,
            records: &mut self.records,
        };
        f(&mut self.parts, &mut ctx)
    }

    /// Routes the events generated through the PPI and settles the inputs, until quiet.
    fn propagate(&mut self, now: u64) {
        self.changed();
        for _ in 0..1000 {
            let settled = self.pins.settle(&mut self.outside, now);
            for (i, level) in settled.edges {
                self.parts.gpiote.on_edge(i, level, &mut self.fired);
            }
            if settled.port_event {
                self.parts.gpiote.on_port(&mut self.fired);
            }
            if self.fired.is_empty() {
                self.check_lfclk(now);
                self.quiet.settled = true;
                return;
            }
            let events = core::mem::take(&mut self.fired);
            for event in events {
                for task in self.parts.ppi.tasks_for(event) {
                    let done = self.with_parts(now, |p, ctx| p.write(task, 1, ctx));
                    if !done {
                        self.records.unmodelled(task, true, 1, now);
                    }
                }
            }
            if self.parts.ppi.fixed_channels_enabled() {
                self.records
                    .note("PPI", "pre-programmed channel enabled (not modelled)", now);
            }
        }
        self.records.note(
            "PPI",
            "events kept triggering each other (stopped after 1000 rounds)",
            now,
        );
    }

    /// Tells the RTCs when the LFCLK starts or stops.
    fn check_lfclk(&mut self, now: u64) {
        let lf = self.parts.clock.lf_timing();
        if lf != self.lf_seen {
            self.changed();
            self.lf_seen = lf;
            for r in &mut self.parts.rtc {
                r.lf_changed(lf, now);
            }
        }
    }

    /// The next internal event, computed once after each change.
    fn next_internal_event(&self) -> u64 {
        if let Some(t) = self.quiet.next_event.get() {
            return t;
        }
        let t = self.parts.next_event_ns().min(self.pins.next_input_ns());
        self.quiet.next_event.set(Some(t));
        t
    }

    /// Something other than a memory access by the CPU happened: the next event and the
    /// inputs' settling are found afresh.
    fn changed(&mut self) {
        self.quiet = Quiet::default();
    }

    /// Brings everything to `now`, each event at its own time.
    fn catch_up(&mut self, now: u64) {
        let mut same = 0u32;
        let mut last = u64::MAX;
        loop {
            let t = self.next_internal_event();
            if t > now {
                break;
            }
            same = if t == last { same + 1 } else { 0 };
            last = t;
            if same > 10_000 {
                self.records
                    .note("SoC", "an event that never clears (skipped ahead)", t);
                break;
            }
            self.now = self.now.max(t);
            self.changed();
            self.pins.apply_inputs(t);
            self.with_parts(t, |p, ctx| p.step(ctx));
            self.propagate(t);
        }
        self.now = self.now.max(now);
    }
}

/// Where an address lies.
#[derive(Clone, Copy)]
enum Region {
    Flash(u32),
    Ram(u32),
    Ficr(u32),
    Uicr(u32),
    Nvmc(u32),
    Peripheral(u32),
    /// A peripheral that exists but is not modelled.
    Absent,
    Gpio(u32),
    Unmapped,
}

impl Region {
    /// Registers, or nothing: a read there may change the chip (memory reads do not).
    const fn is_register(&self) -> bool {
        matches!(
            self,
            Region::Nvmc(_) | Region::Peripheral(_) | Region::Gpio(_) | Region::Absent
        )
    }
}

fn region(addr: u32) -> Region {
    match addr {
        a if a < FLASH_SIZE => Region::Flash(a),
        a if (RAM_BASE..RAM_BASE + RAM_SIZE).contains(&a) => Region::Ram(a),
        a if (FICR_BASE..FICR_BASE + INFO_PAGE_SIZE).contains(&a) => Region::Ficr(a - FICR_BASE),
        a if (UICR_BASE..UICR_BASE + INFO_PAGE_SIZE).contains(&a) => Region::Uicr(a - UICR_BASE),
        a if slot(a) == base::NVMC => Region::Nvmc(a & 0xFFC),
        a if (PERIPH_BASE..PERIPH_END).contains(&a) => {
            if Parts::owns(slot(a)) {
                Region::Peripheral(a)
            } else if peripheral_exists((a >> 12) & 0x3F) {
                Region::Absent
            } else {
                Region::Unmapped
            }
        }
        a if (GPIO_BASE..GPIO_END).contains(&a) => Region::Gpio(a - GPIO_BASE),
        // CRYPTOCELL's slot on the AHB.
        a if slot(a) == 0x5002_A000 => Region::Absent,
        _ => Region::Unmapped,
    }
}

/// Bytes `width` of a word read at `addr` (byte lanes by the address's low bits).
fn lane(word: u32, addr: u32, width: Width) -> u32 {
    let shift = 8 * (addr & 3);
    let value = word >> shift;
    match width {
        Width::Byte => value & 0xFF,
        Width::Half => value & 0xFFFF,
        Width::Word => value,
    }
}

/// Cycles of the core clock in `ns`, rounded up.
fn cycles(ns: u64) -> u32 {
    let c = (u128::from(ns) * u128::from(CORE_HZ)).div_ceil(1_000_000_000);
    u32::try_from(c).unwrap_or(u32::MAX)
}

impl<O: Outside> Nrf52840<O> {
    /// A CPU lock-up resets the nRF52840 (PS "Reset": RESETREAS.LOCKUP; the watchdog runs
    /// on). The core reports a lock-up as `Stop::Lockup`; the runner calls this, then
    /// resets the core.
    pub fn lockup_reset(&mut self) {
        self.reset_as(ResetCause::Other, resetreas::LOCKUP);
    }

    /// A reset for `cause`, recorded in RESETREAS as `reason`.
    fn reset_as(&mut self, cause: ResetCause, reason: u32) {
        self.changed();
        let now = self.now;
        let power_on = cause == ResetCause::PowerOn;
        self.parts.clock.reset(reason, power_on);
        let watchdog_too = cause != ResetCause::Other;
        self.with_parts(now, |p, ctx| p.reset(ctx, watchdog_too));
        self.pins.reset(&mut self.outside, now);
        self.fired.clear();
        self.lf_seen = None;
        if power_on {
            self.ram = Ram::new();
        }
        if let Some(t) = self.asleep_since.take() {
            self.sleep_ns += now.saturating_sub(t);
        }
        self.latch_uicr();
        self.resets.push(ResetRecord { at_ns: now, cause });
    }

    /// Cycles an access to flash waits while the NVMC writes or erases (the CPU is halted
    /// on flash meanwhile, PS "NVMC"); each wait is reported once.
    #[inline]
    fn nvmc_stall(&mut self) -> u32 {
        let busy = self.parts.nvmc.busy_until();
        let from = self.now.max(self.stall_reported_until);
        if busy <= from {
            return 0;
        }
        self.stall_reported_until = busy;
        cycles(busy - from)
    }

    fn peripheral_write(&mut self, addr: u32, value: u32, now: u64) -> bool {
        let done = self.with_parts(now, |p, ctx| p.write(addr, value, ctx));
        if slot(addr) == base::GPIOTE {
            self.pins.gpiote_watch = self.parts.gpiote.watch_mask();
        }
        done
    }

    fn flash_store(&mut self, target: Region, width: Width, value: u32, now: u64) {
        if let Err(e) = self.parts.nvmc.program(now, width == Width::Word) {
            self.records.note("NVMC", e, now);
            return;
        }
        match target {
            Region::Flash(a) => {
                self.flash.program_word(a, value);
                self.flash_generation += 1;
            }
            Region::Uicr(o) => {
                self.uicr.program(o, value);
            }
            _ => {}
        }
    }
}

impl<O: Outside> Bus for Nrf52840<O> {
    fn fetch(&mut self, addr: u32) -> Option<u16> {
        let now = self.now;
        match addr {
            a if a < FLASH_SIZE => self.flash.read(a, 2).map(|v| v as u16),
            a if (CODE_RAM_BASE..CODE_RAM_BASE + RAM_SIZE).contains(&a) => {
                self.ram.fetch(a - CODE_RAM_BASE + RAM_BASE, now)
            }
            a if (RAM_BASE..RAM_BASE + RAM_SIZE).contains(&a) => self.ram.fetch(a, now),
            _ => None,
        }
    }

    #[inline]
    fn fetch_stall(&mut self, addr: u32, _sequential: bool) -> u32 {
        self.records.pc = addr;
        if addr >= FLASH_SIZE {
            return 0;
        }
        self.parts.nvmc.fetch_stall(addr) + self.nvmc_stall()
    }

    fn read(&mut self, addr: u32, width: Width, now_ns: u64) -> Result<u32, BusFault> {
        self.catch_up(now_ns);
        let now = self.now;
        let fault = BusFault { addr, write: false };
        let word_addr = addr & !3;
        let target = region(addr);
        if target.is_register() {
            self.changed();
        }
        Ok(match target {
            Region::Flash(a) => self.flash.read(a, width.bytes()).ok_or(fault)?,
            Region::Ram(a) => self.ram.cpu_read(a, width, now).ok_or(fault)?,
            Region::Ficr(o) => match self.ficr.read(o & !3) {
                Some(w) => lane(w, addr, width),
                None => {
                    self.records.unmodelled(word_addr, false, 0, now);
                    lane(0xFFFF_FFFF, addr, width)
                }
            },
            Region::Uicr(o) => lane(self.uicr.word(o), addr, width),
            Region::Nvmc(o) => match self.parts.nvmc.read(o, now) {
                Some(w) => lane(w, addr, width),
                None => {
                    self.records.unmodelled(word_addr, false, 0, now);
                    0
                }
            },
            Region::Peripheral(a) => match self.parts.read(a, now) {
                Some(w) => lane(w, addr, width),
                None => {
                    self.records.unmodelled(word_addr, false, 0, now);
                    0
                }
            },
            Region::Gpio(o) => {
                let value = self.pins.read(o & !3, &mut self.outside, now);
                match value {
                    Some(w) => lane(w, addr, width),
                    None => {
                        self.records.unmodelled(word_addr, false, 0, now);
                        0
                    }
                }
            }
            Region::Absent => {
                self.records.unmodelled(word_addr, false, 0, now);
                0
            }
            Region::Unmapped => return Err(fault),
        })
    }

    fn write(&mut self, addr: u32, width: Width, value: u32, now_ns: u64) -> Result<(), BusFault> {
        self.catch_up(now_ns);
        let now = self.now;
        let word_addr = addr & !3;
        let word = if width == Width::Word {
            value
        } else {
            value << (8 * (addr & 3))
        };
        let peripheral =
            |r: &Region| matches!(r, Region::Peripheral(_) | Region::Nvmc(_) | Region::Gpio(_));
        let target = region(addr);
        let ram = matches!(target, Region::Ram(_));
        if !ram {
            self.changed();
        }
        if width != Width::Word && peripheral(&target) {
            self.records
                .note("SoC", "store narrower than a word to a register", now);
        }
        match target {
            Region::Flash(_) | Region::Uicr(_) => self.flash_store(target, width, value, now),
            Region::Ram(a) => {
                if !self.ram.cpu_write(a, width, value, now) {
                    return Err(BusFault { addr, write: true });
                }
            }
            Region::Ficr(_) => self
                .records
                .note("FICR", "store to the read-only FICR", now),
            Region::Nvmc(o) => {
                match self
                    .parts
                    .nvmc
                    .write(o, word, now, &mut self.flash, &mut self.uicr)
                {
                    None => self.records.unmodelled(word_addr, true, word, now),
                    Some(Err(e)) => self.records.note("NVMC", e, now),
                    Some(Ok(changed)) => {
                        if changed {
                            self.flash_generation += 1;
                        }
                    }
                }
            }
            Region::Peripheral(a) => {
                if !self.peripheral_write(a & !3, word, now) {
                    self.records.unmodelled(word_addr, true, word, now);
                }
            }
            Region::Gpio(o) => {
                if !self.pins.write(o & !3, word, &mut self.outside, now) {
                    self.records.unmodelled(word_addr, true, word, now);
                }
            }
            Region::Absent => self.records.unmodelled(word_addr, true, word, now),
            Region::Unmapped => return Err(BusFault { addr, write: true }),
        }
        // A store to RAM changes no input: settled inputs stay settled.
        if !(ram && self.quiet.settled) {
            self.propagate(now);
        }
        Ok(())
    }

    fn access_stall(&mut self, addr: u32, write: bool) -> u32 {
        if addr < FLASH_SIZE && !write {
            return self.config.flash_timing.wait_states + self.nvmc_stall();
        }
        0
    }

    fn code_generation(&self) -> u64 {
        self.flash_generation + self.ram.generation
    }

    fn irq_lines(&self) -> [u32; 8] {
        if let Some(lines) = self.quiet.irq_lines.get() {
            return lines;
        }
        let lines = self.parts.irq_lines();
        self.quiet.irq_lines.set(Some(lines));
        lines
    }

    fn next_event_ns(&self) -> u64 {
        self.next_internal_event()
    }

    fn advance(&mut self, now_ns: u64) {
        self.catch_up(now_ns);
    }

    fn core_hz(&self) -> u32 {
        CORE_HZ
    }

    fn take_reset_request(&mut self) -> Option<ResetCause> {
        self.parts.wdt.take_reset().then_some(ResetCause::Watchdog)
    }

    fn reset(&mut self, cause: ResetCause) {
        let reason = match cause {
            ResetCause::Watchdog => resetreas::DOG,
            ResetCause::PowerOn => 0,
            ResetCause::Other => resetreas::SREQ,
        };
        self.reset_as(cause, reason);
    }

    fn sleeping(&mut self, asleep: bool, now_ns: u64) {
        self.catch_up(now_ns);
        let now = self.now;
        if asleep {
            self.asleep_since.get_or_insert(now);
        } else if let Some(t) = self.asleep_since.take() {
            self.sleep_ns += now.saturating_sub(t);
        }
        self.parts.wdt.sleeping(asleep, now);
        self.changed();
    }
}
