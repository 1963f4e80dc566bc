//! The STM32F405RG of the flight images, register by register: [`Stm32f405`] is an
//! [`m4_sim::Bus`] (memories and peripherals around the Cortex-M4F core) that drives its
//! board through [`crate::wire::Outside`].
//!
#![doc = include_str!("README.md")]
//!
//! The files, one concept each:
//! - [`map`]: addresses and IRQ numbers; [`memory`]: flash, SRAM, CCM, OTP and ELF loading;
//! - [`mcu`]: the chip with its core running an image (the co-simulation's `Machine`);
//! - [`rcc`], [`flash`]: clocks and resets, the flash interface with the ART cycle model;
//! - [`gpio`], [`exti`], [`timer`], [`dma`], [`spi`], [`i2c`], [`usart`], [`adc`], [`dac`],
//!   [`iwdg`], [`rng`], [`otg`] (USB OTG FS device core) and [`usb_host`] (the host on its
//!   cable): the peripherals;
//! - `access` (bus dispatch), `schedule` (virtual time, DMA, interrupt lines): the glue;
//! - [`diag`]: what the image touched that is not modelled, and rule breaks.
//!
//! Time: every block keeps its own next event; a register access first brings the chip up
//! to the access's time (`catch_up`), so state read is state at that instant, and board
//! calls carry the exact time of the edge or byte. [`m4_sim::Bus::next_event_ns`] names
//! only events that can change an interrupt line, a DMA request or reset the chip; the rest
//! (PWM edges of timers without interrupts, say) are processed when time passes them.

mod access;
pub mod adc;
#[cfg(test)]
mod boot_tests;
pub mod dac;
pub mod diag;
pub mod dma;
pub mod exti;
pub mod flash;
pub mod gpio;
pub mod i2c;
pub mod iwdg;
pub mod map;
pub mod mcu;
pub mod memory;
pub mod otg;
pub mod rcc;
pub mod rng;
mod schedule;
pub mod spi;
#[cfg(test)]
mod testing;
#[cfg(test)]
mod tests;
pub mod timer;
pub mod usart;
pub mod usb_host;

use m4_sim::bus::ResetCause;

use crate::wire::{Outside, Pin};

use adc::Adc;
use dac::{Dac, DacSample};
use diag::{Diagnostics, Unmodelled, Violation};
use dma::Dma;
use exti::Exti;
use flash::{ArtStats, Erase, FlashIf, FlashTiming};
use gpio::{Gpio, Signal};
use i2c::I2c;
use iwdg::Iwdg;
use memory::{LoadError, Memory};
use otg::Otg;
use rcc::{Clocks, Rcc, ResetKind};
use rng::Rng;
use spi::{Spi, SpiConfig};
use timer::{PulseRecord, PwmSetting, Timer};
use usart::Usart;

/// Board facts and run options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// The crystal or resonator on PH0/PH1 (both boards: 8 MHz).
    pub hse_hz: u32,
    /// This part's LSI, within DS8626's 17–47 kHz (typical 32 kHz).
    pub lsi_hz: u32,
    /// Seeds the RNG, the unique ID and power-on RAM contents.
    pub seed: u64,
    /// Which column of the flash programming times.
    pub flash_timing: FlashTiming,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            hse_hz: 8_000_000,
            lsi_hz: rcc::LSI_TYPICAL_HZ,
            seed: 1,
            flash_timing: FlashTiming::Typical,
        }
    }
}

/// Where an image starts: its vector table, initial stack pointer and reset handler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Entry {
    /// Address of the vector table.
    pub vector_table: u32,
    /// Word 0: the initial MSP.
    pub initial_sp: u32,
    /// Word 1: the reset handler (Thumb bit set).
    pub reset_pc: u32,
}

/// Busy and sleeping time, as the core reports it through [`m4_sim::Bus::sleeping`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CpuTime {
    /// Time awake, ns.
    pub busy_ns: u64,
    /// Time asleep (WFI/WFE), ns.
    pub asleep_ns: u64,
}

/// The four timers the images use, in a fixed order.
pub(crate) const TIMER_KINDS: [timer::TimerKind; 4] =
    [timer::TIM2, timer::TIM3, timer::TIM6, timer::TIM9];

/// The chip.
pub struct Stm32f405<O: Outside> {
    pub(crate) outside: O,
    pub(crate) config: Config,
    pub(crate) mem: Memory,
    pub(crate) rcc: Rcc,
    pub(crate) flash: FlashIf,
    pub(crate) gpio: Gpio,
    pub(crate) exti: Exti,
    /// TIM2, TIM3, TIM6, TIM9.
    pub(crate) timers: [Timer; 4],
    pub(crate) dma: [Dma; 2],
    /// SPI1, SPI3.
    pub(crate) spi: [Spi; 2],
    pub(crate) i2c: I2c,
    pub(crate) usart: Usart,
    pub(crate) adc: Adc,
    pub(crate) dac: Dac,
    pub(crate) iwdg: Iwdg,
    pub(crate) rng: Rng,
    pub(crate) otg: Otg,
    /// DBGMCU CR, APB1_FZ, APB2_FZ.
    pub(crate) dbgmcu: [u32; 3],
    pub(crate) diag: Diagnostics,
    pub(crate) clocks: Clocks,
    /// Everything up to this time has happened.
    pub(crate) now: u64,
    /// Cached: the earliest event of any block, and of those that matter to the core.
    pub(crate) next_due: u64,
    pub(crate) next_visible: u64,
    pub(crate) irq: [u32; 8],
    pub(crate) reset_request: Option<(ResetCause, ResetKind)>,
    /// Set by the runner for the next [`m4_sim::Bus::reset`] with `ResetCause::Other`.
    pub(crate) pending_kind: Option<ResetKind>,
    /// Stall cycles of the last data access.
    pub(crate) last_stall: u32,
    /// The last flash-interface write was a bus error (wrong key).
    pub(crate) flash_bus_error: bool,
    /// DMA items are being moved (their register accesses must not recurse).
    pub(crate) servicing_dma: bool,
    /// SRAM 1 KiB pages instructions were fetched from (a write there invalidates code).
    pub(crate) code_pages: u128,
    pub(crate) ram_code_generation: u64,
    /// Levels last seen on each EXTI line's selected pin.
    pub(crate) line_levels: [bool; 16],
    /// The pins I2C1 last used as SCL and SDA.
    pub(crate) i2c_pins: (Pin, Pin),
    pub(crate) cpu: CpuTime,
    pub(crate) asleep_since: Option<u64>,
    pub(crate) awake_since: u64,
    pub(crate) resets: u32,
    pub(crate) watchdog_resets: u32,
    /// Supply on: unpowered, nothing answers (the core locks up and time passes).
    pub(crate) powered: bool,
}

impl<O: Outside> Stm32f405<O> {
    /// A powered-up chip on `outside`, flash erased; the board hears every pin's reset
    /// state at time 0.
    pub fn new(outside: O, config: Config) -> Self {
        let rcc = Rcc::new(config.hse_hz, config.lsi_hz);
        let clocks = rcc.clocks(0);
        let mut soc = Self {
            outside,
            config,
            mem: Memory::new(config.seed),
            rcc,
            flash: FlashIf::new(config.flash_timing),
            gpio: Gpio::new(),
            exti: Exti::new(),
            timers: TIMER_KINDS.map(Timer::new),
            dma: [Dma::new(0), Dma::new(1)],
            spi: [Spi::new(1), Spi::new(3)],
            i2c: I2c::new(1),
            usart: Usart::new(1),
            adc: Adc::new(),
            dac: Dac::new(),
            iwdg: Iwdg::new(config.lsi_hz),
            rng: Rng::new(config.seed),
            otg: Otg::new(),
            dbgmcu: [0; 3],
            diag: Diagnostics::default(),
            clocks,
            now: 0,
            next_due: 0,
            next_visible: 0,
            irq: [0; 8],
            reset_request: None,
            pending_kind: None,
            last_stall: 0,
            flash_bus_error: false,
            servicing_dma: false,
            code_pages: 0,
            ram_code_generation: 0,
            line_levels: [false; 16],
            i2c_pins: (Pin::new(1, 8), Pin::new(1, 9)),
            cpu: CpuTime::default(),
            asleep_since: None,
            awake_since: 0,
            resets: 0,
            watchdog_resets: 0,
            powered: true,
        };
        soc.gpio.refresh(&mut soc.outside, 0);
        soc.on_clock_change(0);
        soc.refresh(0);
        soc
    }

    /// Programs an ELF file's loadable segments into flash, as a programmer would.
    pub fn load_elf(&mut self, elf: &[u8]) -> Result<(), LoadError> {
        self.mem.load_elf(elf)?;
        self.ram_code_generation += 1;
        Ok(())
    }

    /// Writes `data` into flash at `address` directly (a programmer, not the CPU).
    pub fn program_flash(&mut self, address: u32, data: &[u8]) -> Result<(), LoadError> {
        self.mem.program(address, data)?;
        self.ram_code_generation += 1;
        Ok(())
    }

    /// The main flash's contents (offset 0 = 0x0800_0000).
    pub fn flash_contents(&self) -> &[u8] {
        &self.mem.flash
    }

    /// SRAM's contents (offset 0 = 0x2000_0000).
    pub fn sram_contents(&self) -> &[u8] {
        &self.mem.sram
    }

    /// The vector table at `addr` in flash, if its first word is a plausible stack pointer
    /// (inside SRAM or CCM) and its second a Thumb address in flash.
    pub fn entry_at(&self, addr: u32) -> Option<Entry> {
        let off = addr.checked_sub(map::FLASH_BASE)?;
        let sp = memory::load(&self.mem.flash, off, 4)?;
        let pc = memory::load(&self.mem.flash, off + 4, 4)?;
        let ram = (map::SRAM_BASE..=map::SRAM_BASE + map::SRAM_SIZE).contains(&sp)
            || (map::CCM_BASE..=map::CCM_BASE + map::CCM_SIZE).contains(&sp);
        let code = pc & 1 == 1
            && (map::FLASH_BASE..map::FLASH_BASE + map::FLASH_SIZE).contains(&(pc & !1));
        (ram && code).then_some(Entry {
            vector_table: addr,
            initial_sp: sp,
            reset_pc: pc,
        })
    }

    /// Where the loaded image boots: the table at 0x0800_0000 (BOOT0 low), or — an image
    /// linked behind the Tau Labs bootloader with no bootloader loaded — the application
    /// table at 0x0802_0000, which the bootloader would jump to (MSP and PC from it).
    pub fn boot_entry(&self) -> Option<Entry> {
        self.entry_at(map::FLASH_BASE)
            .or_else(|| self.entry_at(map::FLASH_BASE + 0x2_0000))
    }

    /// The board.
    pub fn outside(&self) -> &O {
        &self.outside
    }

    /// The board, mutably.
    pub fn outside_mut(&mut self) -> &mut O {
        &mut self.outside
    }

    /// Queues a level the board puts on input `pin` from `at_ns` on.
    pub fn drive_input(&mut self, pin: Pin, level: bool, at_ns: u64) {
        self.gpio.drive_input(pin, level, at_ns);
        self.refresh(self.now);
    }

    /// Queues a byte arriving on UART `uart` (1 = USART1) at the configured baud rate, its
    /// stop bit ending at `at_ns`.
    pub fn uart_receive(&mut self, uart: u8, byte: u8, at_ns: u64) {
        if uart == self.usart.number {
            self.usart.receive(byte, at_ns);
            self.refresh(self.now);
        }
    }

    /// Queues a byte sent at `baud` (the sender's rate) ending at `end_ns`: at a different
    /// rate than the USART's, it arrives as the receiver samples it.
    pub fn uart_receive_at_baud(&mut self, uart: u8, byte: u8, baud: u32, end_ns: u64) {
        if uart == self.usart.number {
            self.usart.receive_at_baud(byte, baud, end_ns);
            self.refresh(self.now);
        }
    }

    /// The baud rate UART `uart` is set to (0 when unconfigured).
    pub fn uart_baud(&self, uart: u8) -> u32 {
        if uart == self.usart.number {
            self.usart.baud()
        } else {
            0
        }
    }

    /// Bytes USARTx lost to overrun.
    pub fn uart_overruns(&self, uart: u8) -> u64 {
        if uart == self.usart.number {
            self.usart.overruns
        } else {
            0
        }
    }

    /// SPI bus `bus`'s (1 or 3) configuration, for a board checking modes and speeds.
    pub fn spi_config(&self, bus: u8) -> Option<SpiConfig> {
        self.spi.iter().find(|s| s.bus == bus).map(Spi::config)
    }

    /// Sets the LSI frequency (runner's `--lsi-hz`).
    pub fn set_lsi_hz(&mut self, hz: u32) {
        let now = self.now;
        self.rcc.set_lsi_hz(hz);
        self.iwdg.set_lsi_hz(hz, now);
        self.config.lsi_hz = hz;
        self.refresh(now);
    }

    /// Makes the HSE never start (or work again): the missing-clock finding.
    pub fn set_hse_fault(&mut self, fault: bool) {
        self.rcc.set_hse_fault(fault);
    }

    /// Makes the RNG's noise source dead (or alive again): DRDY never rises.
    pub fn set_rng_fault(&mut self, fault: bool) {
        self.rng.set_dead(fault);
    }

    /// Asks for a reset the core will take at its next poll: `Pin` (NRST from outside) or
    /// `PowerOn` (a power cycle).
    pub fn request_reset(&mut self, kind: ResetKind) {
        let cause = match kind {
            ResetKind::PowerOn => ResetCause::PowerOn,
            ResetKind::IndependentWatchdog => ResetCause::Watchdog,
            ResetKind::Pin | ResetKind::Software => ResetCause::Other,
        };
        self.pending_kind = Some(kind);
        self.reset_request = Some((cause, kind));
    }

    /// What timer channel `(timer, ch)` is set to output (TIM3 CH3 = `(3, 3)`).
    pub fn pwm(&self, timer: u8, ch: u8) -> Option<PwmSetting> {
        self.timer_by_number(timer)?.pwm_setting(ch)
    }

    /// The pulses measured on the timer channel that drives `pin` now.
    pub fn pulses(&self, pin: Pin) -> Option<PulseRecord> {
        let (timer, ch) = self.timer_channel_of(pin)?;
        self.timer_by_number(timer)?.pulses(ch)
    }

    /// The timer channel `(timer, ch)` whose output `pin` carries now.
    pub fn timer_channel_of(&self, pin: Pin) -> Option<(u8, u8)> {
        TIMER_KINDS.iter().find_map(|k| {
            (1..=k.channels).find_map(|ch| {
                let s = Signal::Tim {
                    timer: k.number,
                    ch,
                };
                self.gpio
                    .pins_of(s)
                    .contains(&pin)
                    .then_some((k.number, ch))
            })
        })
    }

    pub(crate) fn timer_by_number(&self, n: u8) -> Option<&Timer> {
        self.timers.iter().find(|t| t.kind().number == n)
    }

    /// DAC channel 1's output now (volts; `None` while disabled).
    pub fn dac_output(&self) -> Option<f32> {
        self.dac.output()
    }

    /// Takes DAC channel 1's output history since the last call.
    pub fn take_dac_history(&mut self) -> Vec<DacSample> {
        self.dac.take_history()
    }

    /// Accesses to things the model does not model (a test asserts `boot` leaves it empty).
    pub fn unmodelled(&self) -> &[Unmodelled] {
        self.diag.unmodelled_list()
    }

    /// Uses of the chip the silicon would not honour.
    pub fn violations(&self) -> &[Violation] {
        self.diag.violation_list()
    }

    /// The clock tree now.
    pub fn clocks(&self) -> Clocks {
        self.clocks
    }

    /// The ART accelerator's counters.
    pub fn art_stats(&self) -> ArtStats {
        self.flash.stats()
    }

    /// The flash erases the firmware started (sector or mass), oldest first, across resets.
    pub fn flash_erases(&self) -> &[Erase] {
        self.flash.erases()
    }

    /// The flash wait states configured.
    pub fn flash_latency(&self) -> u32 {
        self.flash.latency()
    }

    /// Watchdog reloads so far and the smallest margin left at one, ns.
    pub fn watchdog_feeds(&self) -> (u64, Option<u64>) {
        (self.iwdg.reloads, self.iwdg.min_margin_ns)
    }

    /// Awake and asleep time.
    pub fn cpu_time(&self) -> CpuTime {
        let mut t = self.cpu;
        match self.asleep_since {
            Some(s) => t.asleep_ns += self.now.saturating_sub(s),
            None => t.busy_ns += self.now.saturating_sub(self.awake_since),
        }
        t
    }

    /// Resets taken so far.
    pub fn resets(&self) -> u32 {
        self.resets
    }

    /// Resets by the independent watchdog so far.
    pub fn watchdog_resets(&self) -> u32 {
        self.watchdog_resets
    }

    /// Removes the supply (`false`: every pin let go, memories and registers lost, the core
    /// finds nothing on its buses) or restores it (a power-on reset the core takes at once).
    pub fn set_powered(&mut self, on: bool) {
        if on == self.powered {
            return;
        }
        self.powered = on;
        if on {
            self.request_reset(ResetKind::PowerOn);
        } else {
            self.irq = [0; 8];
            self.next_visible = u64::MAX;
            self.gpio.release_all(&mut self.outside, self.now);
        }
    }

    /// Whether the supply is on.
    pub fn powered(&self) -> bool {
        self.powered
    }

    /// Puts a stand-in for the Tau Labs bootloader in flash sector 0: a vector table whose
    /// reset handler does what that bootloader does when it hands over — load MSP and PC
    /// from the application's table at `app_table` and jump — so an image linked behind
    /// it boots, and boots again after every reset.
    pub fn install_bootloader_handover(&mut self, app_table: u32) -> Result<(), LoadError> {
        let [a0, a1, a2, a3] = app_table.to_le_bytes();
        let code: [u8; 28] = [
            0x00, 0x00, 0x02, 0x20, // initial MSP: top of SRAM
            0x09, 0x00, 0x00, 0x08, // reset handler at 0x0800_0008, Thumb
            0x03, 0x48, // ldr r0, [pc, #12]  (the application's table)
            0x01, 0x68, // ldr r1, [r0]       (its MSP)
            0x81, 0xF3, 0x08, 0x88, // msr msp, r1
            0x41, 0x68, // ldr r1, [r0, #4]   (its reset handler)
            0x08, 0x47, // bx r1
            0x00, 0x00, 0x00, 0x00, // padding to the literal at 0x18
            a0, a1, a2, a3,
        ];
        self.program_flash(map::FLASH_BASE, &code)
    }

    /// The USB host on the OTG FS port (the runner's console): its state and log.
    pub fn usb_host(&self) -> &usb_host::UsbHost {
        self.otg.host()
    }

    /// Plugs a USB host into the OTG FS port (or pulls it) now.
    pub fn usb_plug(&mut self, plugged: bool) {
        let now = self.now;
        self.otg.plug(plugged, now);
        self.refresh(now);
    }

    /// Types `bytes` into the CDC ACM console (sent once the host has enumerated).
    pub fn usb_send(&mut self, bytes: &[u8]) {
        let now = self.now;
        self.otg.send(bytes, now);
        self.refresh(now);
    }

    /// What the firmware wrote to the console since the last call.
    pub fn usb_take_received(&mut self) -> Vec<u8> {
        self.otg.take_received()
    }

    /// Time up to which everything has happened.
    pub fn now_ns(&self) -> u64 {
        self.now
    }
}

impl<O: Outside> m4_sim::Bus for Stm32f405<O> {
    fn fetch(&mut self, addr: u32) -> Option<u16> {
        if !self.powered {
            return None;
        }
        self.fetch_halfword(addr)
    }

    #[inline]
    fn fetch_stall(&mut self, addr: u32, _sequential: bool) -> u32 {
        // Called for every instruction: the flash test first, without the full decode.
        let off = addr.wrapping_sub(map::FLASH_BASE);
        let off = if off < map::FLASH_SIZE {
            off
        } else if addr < map::FLASH_SIZE && self.exti.mem_mode() == 0 {
            addr
        } else {
            return 0;
        };
        self.flash.fetch_stall(off, self.now, self.clocks.hclk)
    }

    fn read(
        &mut self,
        addr: u32,
        width: m4_sim::Width,
        now_ns: u64,
    ) -> Result<u32, m4_sim::BusFault> {
        if !self.powered {
            return Err(m4_sim::BusFault { addr, write: false });
        }
        self.bus_read(addr, width, now_ns)
    }

    fn write(
        &mut self,
        addr: u32,
        width: m4_sim::Width,
        value: u32,
        now_ns: u64,
    ) -> Result<(), m4_sim::BusFault> {
        if !self.powered {
            return Err(m4_sim::BusFault { addr, write: true });
        }
        self.bus_write(addr, width, value, now_ns)
    }

    fn access_stall(&mut self, _addr: u32, _write: bool) -> u32 {
        std::mem::take(&mut self.last_stall)
    }

    fn code_generation(&self) -> u64 {
        self.flash.generation() + self.ram_code_generation
    }

    fn irq_lines(&self) -> [u32; 8] {
        self.irq
    }

    fn next_event_ns(&self) -> u64 {
        self.next_visible
    }

    fn advance(&mut self, now_ns: u64) {
        if self.powered {
            self.catch_up(now_ns);
        } else if now_ns > self.now {
            self.now = now_ns;
        }
    }

    fn core_hz(&self) -> u32 {
        self.clocks.hclk
    }

    fn take_reset_request(&mut self) -> Option<ResetCause> {
        self.reset_request.map(|(c, _)| c)
    }

    fn reset(&mut self, cause: ResetCause) {
        self.system_reset(cause);
    }

    fn sysresetreq(&mut self) {
        self.pending_kind = Some(ResetKind::Software);
        self.system_reset(ResetCause::Other);
    }

    fn sleeping(&mut self, asleep: bool, now_ns: u64) {
        self.account_sleep(asleep, now_ns);
    }
}
