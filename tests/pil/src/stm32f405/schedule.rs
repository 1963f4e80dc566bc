//! Virtual time and the wiring between blocks: processing events in time order, the DMA
//! requests served, timer outputs onto pins and TRGO into the DAC, pin levels into EXTI
//! and I2C, the interrupt lines, clock changes, resets and sleep accounting.

use m4_sim::Width;
use m4_sim::bus::ResetCause;

use super::dac::Trigger;
use super::dma::{Direction, Outcome, Request};
use super::gpio::{LevelChange, Signal, SignalDrive};
use super::map::{self, Block, irq};
use super::rcc::ResetKind;
use super::{Stm32f405, TIMER_KINDS, memory};
use crate::wire::{Outside, Pin};

/// Events one instant may take before the model declares itself stuck.
const MAX_EVENTS_AT_ONE_INSTANT: u32 = 100_000;
/// DMA items one service pass may move (a full 64 KiB block is the most a stream holds).
const MAX_DMA_ITEMS: u32 = 1 << 17;

/// The block of timer number `n`.
fn timer_block(n: u8) -> Block {
    match n {
        2 => Block::Tim2,
        3 => Block::Tim3,
        6 => Block::Tim6,
        _ => Block::Tim9,
    }
}

/// The DAC trigger a timer's TRGO is.
fn trigger_of(n: u8) -> Option<Trigger> {
    match n {
        2 => Some(Trigger::Tim2),
        6 => Some(Trigger::Tim6),
        _ => None,
    }
}

impl<O: Outside> Stm32f405<O> {
    /// Processes every event due by `now`, in time order; stops at a reset request.
    pub(crate) fn catch_up(&mut self, now: u64) {
        let mut last = u64::MAX;
        let mut same = 0u32;
        while self.reset_request.is_none() {
            let t = self.next_due;
            if t > now {
                break;
            }
            if t == last {
                same += 1;
                if same > MAX_EVENTS_AT_ONE_INSTANT {
                    self.diag
                        .violation("model error: an event did not advance (skipped)", t);
                    self.next_due = t + 1;
                    continue;
                }
            } else {
                (last, same) = (t, 0);
            }
            self.process_at(t);
        }
        if self.reset_request.is_none() && now > self.now {
            self.now = now;
        }
    }

    /// Processes the events of every block due at `t` (the earliest of all).
    fn process_at(&mut self, t: u64) {
        if t > self.now {
            self.now = t;
        }
        if t < self.next_visible {
            // Only timers nobody listens to act now (PWM edges): no line, no DMA request
            // and no other block's event changes.
            self.process_quiet_timers(t);
            return;
        }
        if self.rcc.next_event() <= t && self.rcc.process(t) {
            self.on_clock_change(t);
        }
        if self.flash.next_event() <= t {
            self.flash.process(t);
        }
        if self.gpio.next_event() <= t {
            let changes = self.gpio.process(t, &mut self.outside);
            self.inputs_changed(&changes);
        }
        for timer in &mut self.timers {
            if timer.next_event() <= t {
                timer.process(t);
            }
        }
        self.forward_timer_outputs();
        for spi in &mut self.spi {
            if spi.next_event() <= t {
                spi.process(t, &mut self.outside);
            }
        }
        if self.i2c.next_event() <= t {
            let left = self.i2c_dma_rx_left();
            self.i2c.process(t, &mut self.outside, left);
        }
        if self.usart.next_event() <= t {
            self.usart.process(t, &mut self.outside);
        }
        if self.adc.next_event() <= t {
            self.adc.process(t, &mut self.outside);
        }
        if self.iwdg.next_event() <= t && self.iwdg.process(t) {
            self.reset_request = Some((ResetCause::Watchdog, ResetKind::IndependentWatchdog));
        }
        if self.otg.next_event() <= t {
            self.otg.process(t);
        }
        self.service_dma(t);
        self.refresh(t);
    }

    /// The timers' own events at `t`, when nothing else happens then.
    fn process_quiet_timers(&mut self, t: u64) {
        let mut due = self.next_visible;
        for timer in &mut self.timers {
            if timer.next_event() <= t {
                timer.process(t);
            }
            due = due.min(timer.next_event());
        }
        self.forward_timer_outputs();
        self.next_due = due;
    }

    /// Items left on the DMA stream serving I2C1's receive request.
    fn i2c_dma_rx_left(&self) -> Option<u32> {
        let d = self.dma.first()?;
        d.stream_for(Request::I2c1Rx).map(|s| d.remaining(s))
    }

    /// After an access to `block`: its outputs to the pins, DMA, lines and next events.
    pub(crate) fn after_access(&mut self, block: Block, now: u64) {
        if self.servicing_dma {
            return;
        }
        match block {
            Block::Tim2 | Block::Tim3 | Block::Tim6 | Block::Tim9 => self.forward_timer_outputs(),
            Block::Spi1 | Block::Spi3 | Block::Usart1 => self.sync_signals(now),
            Block::Rcc => {
                self.forward_timer_outputs();
                self.sync_signals(now);
            }
            _ => {}
        }
        self.service_dma(now);
        self.refresh(now);
    }

    /// Timer output changes onto their pins, TRGO pulses into the DAC.
    fn forward_timer_outputs(&mut self) {
        for i in 0..self.timers.len() {
            let Some(timer) = self.timers.get_mut(i) else {
                continue;
            };
            if timer.changes.is_empty() && timer.trgo.is_empty() {
                continue;
            }
            let number = timer.kind().number;
            let changes = std::mem::take(&mut timer.changes);
            let trgo = std::mem::take(&mut timer.trgo);
            for (ch, drive, t) in changes {
                self.gpio.set_signal(
                    Signal::Tim { timer: number, ch },
                    drive,
                    &mut self.outside,
                    t,
                );
            }
            if let Some(source) = trigger_of(number) {
                for t in trgo {
                    self.dac.trigger(source, t);
                }
            }
        }
    }

    /// The idle levels SPI and USART hold on their pins.
    fn sync_signals(&mut self, now: u64) {
        for i in 0..self.spi.len() {
            let Some(spi) = self.spi.get(i) else { continue };
            let (bus, sck) = (spi.bus, spi.sck_idle());
            let sck_drive = sck.map_or(SignalDrive::Off, SignalDrive::Level);
            let mosi_drive = sck.map_or(SignalDrive::Off, |_| SignalDrive::Level(false));
            self.gpio
                .set_signal(Signal::SpiSck(bus), sck_drive, &mut self.outside, now);
            self.gpio
                .set_signal(Signal::SpiMosi(bus), mosi_drive, &mut self.outside, now);
        }
        let tx = if self.usart.tx_enabled() {
            SignalDrive::Level(true)
        } else {
            SignalDrive::Off
        };
        self.gpio.set_signal(
            Signal::UsartTx(self.usart.number),
            tx,
            &mut self.outside,
            now,
        );
    }

    /// Serves every active DMA request, highest priority first.
    pub(crate) fn service_dma(&mut self, now: u64) {
        if self.servicing_dma {
            return;
        }
        self.servicing_dma = true;
        let stall = self.last_stall;
        for _ in 0..MAX_DMA_ITEMS {
            if !self.dma_step(now) {
                break;
            }
        }
        self.last_stall = stall;
        self.servicing_dma = false;
    }

    /// Moves one item if any stream has an active request; false if none did.
    fn dma_step(&mut self, now: u64) -> bool {
        for c in 0..self.dma.len() {
            let Some(dma) = self.dma.get(c) else { continue };
            if !dma.active() {
                continue;
            }
            let served = dma
                .requesting()
                .find(|&(_, req)| self.request_active(req))
                .map(|(stream, _)| stream)
                .or_else(|| dma.memory_to_memory());
            if let Some(stream) = served {
                self.dma_move(c, stream, now);
                return true;
            }
        }
        false
    }

    fn request_active(&self, req: Request) -> bool {
        let [spi1, spi3] = &self.spi;
        match req {
            Request::Spi1Tx => spi1.tx_request(),
            Request::Spi1Rx => spi1.rx_request(),
            Request::Spi3Tx => spi3.tx_request(),
            Request::Spi3Rx => spi3.rx_request(),
            Request::I2c1Tx => self.i2c.tx_request(),
            Request::I2c1Rx => self.i2c.rx_request(),
            Request::Usart1Tx => self.usart.tx_request(),
            Request::Usart1Rx => self.usart.rx_request(),
            Request::Dac1 => self.dac.dma_request(),
            Request::Adc1 => self.adc.dma_request(),
        }
    }

    fn dma_move(&mut self, c: usize, stream: usize, now: u64) {
        let Some(dma) = self.dma.get(c) else { return };
        let Some(item) = dma.item(stream) else { return };
        let periph_port_is_peripheral = item.dir != Direction::MemoryToMemory;
        let reach = dma
            .reach_error(item.periph_addr, periph_port_is_peripheral)
            .or_else(|| dma.reach_error(item.mem_addr, false));
        let width = match item.size {
            1 => Width::Byte,
            2 => Width::Half,
            _ => Width::Word,
        };
        let ok = reach.is_none()
            && match item.dir {
                Direction::PeripheralToMemory | Direction::MemoryToMemory => self
                    .dma_read(item.periph_addr, width, now)
                    .and_then(|v| self.dma_write_memory(item.mem_addr, width, v))
                    .is_some(),
                Direction::MemoryToPeripheral => self
                    .dma_read(item.mem_addr, width, now)
                    .and_then(|v| {
                        self.peripheral_write(item.periph_addr, width, v, now, true)
                            .ok()
                    })
                    .is_some(),
            };
        if let Some(e) = reach {
            self.diag.violation(&e, now);
        }
        if let Some(dma) = self.dma.get_mut(c) {
            dma.complete(stream, if ok { Outcome::Done } else { Outcome::BusError });
        }
    }

    fn dma_read(&mut self, addr: u32, width: Width, now: u64) -> Option<u32> {
        let bytes = width.bytes();
        if addr >= 0x4000_0000 {
            if let Some(o) = addr
                .checked_sub(map::BKPSRAM_BASE)
                .filter(|&o| o < map::BKPSRAM_SIZE)
            {
                return memory::load(&self.mem.bkpsram, o, bytes);
            }
            return self.peripheral_read(addr, width, now).ok();
        }
        if let Some(o) = addr
            .checked_sub(map::SRAM_BASE)
            .filter(|&o| o < map::SRAM_SIZE)
        {
            return memory::load(&self.mem.sram, o, bytes);
        }
        let o = addr
            .checked_sub(map::FLASH_BASE)
            .filter(|&o| o < map::FLASH_SIZE)?;
        memory::load(&self.mem.flash, o, bytes)
    }

    fn dma_write_memory(&mut self, addr: u32, width: Width, value: u32) -> Option<()> {
        let bytes = width.bytes();
        if let Some(o) = addr
            .checked_sub(map::SRAM_BASE)
            .filter(|&o| o < map::SRAM_SIZE)
        {
            return memory::store(&mut self.mem.sram, o, bytes, value).then_some(());
        }
        if let Some(o) = addr
            .checked_sub(map::BKPSRAM_BASE)
            .filter(|&o| o < map::BKPSRAM_SIZE)
        {
            return memory::store(&mut self.mem.bkpsram, o, bytes, value).then_some(());
        }
        if addr >= 0x4000_0000 {
            return self
                .peripheral_write(addr, width, value, self.now, true)
                .ok();
        }
        None
    }

    /// Queued input levels changed at their times: EXTI edges, I2C lines.
    fn inputs_changed(&mut self, changes: &[LevelChange]) {
        for c in changes {
            self.pin_level_changed(c.pin, c.at_ns);
        }
    }

    /// Pins whose drive changed by a GPIO write.
    pub(crate) fn pins_changed(&mut self, pins: &[Pin], now: u64) {
        for &p in pins {
            self.pin_level_changed(p, now);
        }
    }

    fn pin_level_changed(&mut self, pin: Pin, t: u64) {
        if self.exti.port_of(pin.pin) == pin.port {
            self.update_exti_line(pin.pin, t);
        }
        if pin == self.i2c_pins.0 || pin == self.i2c_pins.1 {
            self.observe_i2c_lines(t);
        }
    }

    fn update_exti_line(&mut self, line: u8, t: u64) {
        let pin = Pin::new(self.exti.port_of(line), line);
        let level = self.gpio.level(pin, &mut self.outside, t);
        if let Some(l) = self.line_levels.get_mut(usize::from(line))
            && *l != level
        {
            *l = level;
            self.exti.edge(line, level);
        }
    }

    /// SYSCFG changed a line's pin: take its level without an edge.
    pub(crate) fn resync_exti_lines(&mut self, now: u64) {
        for line in 0..16u8 {
            let pin = Pin::new(self.exti.port_of(line), line);
            let level = self.gpio.level(pin, &mut self.outside, now);
            if let Some(l) = self.line_levels.get_mut(usize::from(line)) {
                *l = level;
            }
        }
    }

    /// Shows I2C1 the levels of its SCL and SDA pins.
    pub(crate) fn observe_i2c_lines(&mut self, now: u64) {
        let scl = self.gpio.pins_of(Signal::I2cScl(1));
        let sda = self.gpio.pins_of(Signal::I2cSda(1));
        if let (Some(&scl), Some(&sda)) = (scl.first(), sda.first()) {
            self.i2c_pins = (scl, sda);
        }
        let (scl_pin, sda_pin) = self.i2c_pins;
        let scl = self.gpio.level_opt(scl_pin, &mut self.outside, now);
        let sda = self.gpio.level_opt(sda_pin, &mut self.outside, now);
        if let (Some(scl), Some(sda)) = (scl, sda) {
            self.i2c.observe_lines(scl, sda, now);
        }
    }

    /// Recomputes interrupt lines and next events after anything changed.
    pub(crate) fn refresh(&mut self, now: u64) {
        if !self.powered {
            self.irq = [0; 8];
            self.next_due = u64::MAX;
            self.next_visible = u64::MAX;
            return;
        }
        self.drain_notes(now);
        let mut lines = [0u32; 8];
        let mut set = |n: u32| {
            if let Some(w) = lines.get_mut((n / 32) as usize) {
                *w |= 1 << (n % 32);
            }
        };
        if self.flash.irq() {
            set(irq::FLASH);
        }
        self.exti.irqs().for_each(&mut set);
        for d in &self.dma {
            d.irqs().for_each(&mut set);
        }
        if self.adc.irq() {
            set(irq::ADC);
        }
        for t in &self.timers {
            let n = match t.kind().number {
                2 => irq::TIM2,
                3 => irq::TIM3,
                6 => irq::TIM6_DAC,
                _ => irq::TIM1_BRK_TIM9,
            };
            if t.irq() {
                set(n);
            }
        }
        if self.dac.irq() {
            set(irq::TIM6_DAC);
        }
        if self.i2c.ev_irq() {
            set(irq::I2C1_EV);
        }
        if self.i2c.er_irq() {
            set(irq::I2C1_ER);
        }
        let [spi1, spi3] = &self.spi;
        if spi1.irq() {
            set(irq::SPI1);
        }
        if spi3.irq() {
            set(irq::SPI3);
        }
        if self.usart.irq() {
            set(irq::USART1);
        }
        if self.rng.irq(now) {
            set(irq::HASH_RNG);
        }
        if self.otg.irq() {
            set(irq::OTG_FS);
        }
        self.irq = lines;

        let mut due = self
            .rcc
            .next_event()
            .min(self.flash.next_event())
            .min(self.gpio.next_event())
            .min(self.i2c.next_event())
            .min(self.usart.next_event())
            .min(self.adc.next_event())
            .min(self.iwdg.next_event())
            .min(self.rng.next_event())
            .min(self.otg.next_event());
        for s in &self.spi {
            due = due.min(s.next_event());
        }
        let mut visible = due;
        for t in &self.timers {
            let next = t.next_event();
            due = due.min(next);
            let trgo_used =
                trigger_of(t.kind().number).is_some_and(|s| self.dac.listens_with_dma(s));
            if t.visible(trgo_used) {
                visible = visible.min(next);
            }
        }
        self.next_due = due;
        self.next_visible = visible;
    }

    /// Moves the blocks' notes into the diagnostics.
    fn drain_notes(&mut self, now: u64) {
        for t in &mut self.timers {
            if t.unmodelled.is_empty() {
                continue;
            }
            let base = map::base_of(timer_block(t.kind().number));
            for u in t.unmodelled.drain(..) {
                self.diag.unmodelled(base, true, 0, u, now);
            }
        }
        for (c, d) in self.dma.iter_mut().enumerate() {
            if d.unmodelled.is_empty() && d.violations.is_empty() {
                continue;
            }
            let base = map::base_of(Block::Dma(c as u8));
            for u in d.unmodelled.drain(..) {
                self.diag.unmodelled(base, true, 0, u, now);
            }
            for v in d.violations.drain(..) {
                self.diag.violation(&v, now);
            }
        }
        for s in &mut self.spi {
            if s.unmodelled.is_empty() && s.violations.is_empty() {
                continue;
            }
            let base = map::base_of(if s.bus == 1 { Block::Spi1 } else { Block::Spi3 });
            for u in s.unmodelled.drain(..) {
                self.diag.unmodelled(base, true, 0, u, now);
            }
            for v in s.violations.drain(..) {
                self.diag.violation(v, now);
            }
        }
        let blocks: [(Block, &mut Vec<&'static str>); 4] = [
            (Block::I2c1, &mut self.i2c.unmodelled),
            (Block::Usart1, &mut self.usart.unmodelled),
            (Block::Adc1, &mut self.adc.unmodelled),
            (Block::Dac, &mut self.dac.unmodelled),
        ];
        for (block, notes) in blocks {
            if !notes.is_empty() {
                let base = map::base_of(block);
                for u in notes.drain(..) {
                    self.diag.unmodelled(base, true, 0, u, now);
                }
            }
        }
        for u in self.otg.unmodelled.drain(..) {
            self.diag
                .unmodelled(map::base_of(Block::OtgFs), true, 0, u, now);
        }
        for v in self.i2c.violations.drain(..) {
            self.diag.violation(&v, now);
        }
        for v in self.adc.violations.drain(..) {
            self.diag.violation(v, now);
        }
        for (pin, af) in self.gpio.unrouted.drain(..) {
            let base = map::base_of(Block::Gpio(pin.port));
            let what = format!(
                "P{}{} on AF{af}: no modelled peripheral drives it",
                char::from(b'A' + pin.port),
                pin.pin
            );
            self.diag
                .unmodelled(base + 0x20, true, u32::from(af), &what, now);
        }
    }

    /// The clock tree or an enable changed: every block takes its new clock.
    pub(crate) fn on_clock_change(&mut self, now: u64) {
        let c = self.rcc.clocks(now);
        let changed = c != self.clocks;
        self.clocks = c;
        for i in 0..self.timers.len() {
            let Some(kind) = TIMER_KINDS.get(i) else {
                continue;
            };
            let hz = if !self.rcc.clocked(timer_block(kind.number)) {
                0
            } else if kind.number == 9 {
                c.tim_apb2
            } else {
                c.tim_apb1
            };
            if let Some(t) = self.timers.get_mut(i) {
                t.set_clock(hz, now);
            }
        }
        let [spi1, spi3] = &mut self.spi;
        spi1.set_pclk(c.pclk2);
        spi3.set_pclk(c.pclk1);
        self.i2c.set_pclk(c.pclk1);
        self.usart.set_pclk(c.pclk2);
        self.adc.set_pclk2(c.pclk2);
        self.rng.set_clocks(c.pll48, c.hclk, now);
        self.otg.set_clock_ok(c.pll48 == 48_000_000);
        if changed {
            self.check_flash_latency(now);
        }
    }

    /// Records too few flash wait states for the clock (RM0090 Table 10).
    pub(crate) fn check_flash_latency(&mut self, now: u64) {
        let hclk = self.clocks.hclk;
        if self.flash.latency_too_low(hclk) {
            let text = format!(
                "flash LATENCY {} below the {} wait states HCLK {} MHz needs (RM0090 Table 10): reads would fail",
                self.flash.latency(),
                super::flash::required_latency(hclk),
                hclk / 1_000_000
            );
            self.diag.violation(&text, now);
        }
    }

    /// An RCC reset bit pulsed `block`.
    pub(crate) fn reset_block(&mut self, block: Block, now: u64) {
        match block {
            Block::Gpio(port) => {
                self.gpio.reset_port(usize::from(port));
                let pins = self.gpio.refresh(&mut self.outside, now);
                self.pins_changed(&pins, now);
            }
            Block::Dma(c) => {
                if let Some(d) = self.dma.get_mut(usize::from(c)) {
                    d.reset();
                }
            }
            Block::Tim2 | Block::Tim3 | Block::Tim6 | Block::Tim9 => {
                if let Some(t) =
                    super::access::timer_index(block).and_then(|i| self.timers.get_mut(i))
                {
                    t.reset(now);
                }
                self.forward_timer_outputs();
            }
            Block::Spi1 => self.spi[0].reset(),
            Block::Spi3 => self.spi[1].reset(),
            Block::I2c1 => self.i2c.reset(),
            Block::Usart1 => self.usart.reset(),
            Block::Adc1 | Block::AdcCommon => self.adc.reset(),
            Block::Dac => self.dac.reset(now),
            Block::Syscfg => self.exti.reset_syscfg(),
            Block::Rng => self.rng.reset(),
            Block::OtgFs => self.otg.reset(),
            _ => {}
        }
    }

    /// A system reset: every block to its reset state; RAM kept unless power was lost.
    pub(crate) fn system_reset(&mut self, cause: ResetCause) {
        let kind = match cause {
            ResetCause::Watchdog => ResetKind::IndependentWatchdog,
            ResetCause::PowerOn => ResetKind::PowerOn,
            ResetCause::Other => self.pending_kind.unwrap_or(ResetKind::Software),
        };
        self.pending_kind = None;
        self.reset_request = None;
        let now = self.now;
        self.rcc.reset(kind);
        self.flash.reset(&mut self.mem.flash, now);
        self.gpio.reset();
        self.exti = super::exti::Exti::new();
        for t in &mut self.timers {
            t.reset(now);
        }
        for d in &mut self.dma {
            d.reset();
        }
        for s in &mut self.spi {
            s.reset();
        }
        self.i2c.reset();
        self.usart.reset();
        self.adc.reset();
        self.dac.reset(now);
        self.iwdg.reset();
        self.rng.reset();
        self.otg.reset();
        if kind == ResetKind::PowerOn {
            self.dbgmcu = [0; 3];
            let seed =
                self.config.seed ^ u64::from(self.resets + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            self.mem.power_on(seed);
        }
        self.resets += 1;
        if kind == ResetKind::IndependentWatchdog {
            self.watchdog_resets += 1;
        }
        self.line_levels = [false; 16];
        self.code_pages = 0;
        self.ram_code_generation += 1;
        self.forward_timer_outputs();
        self.gpio.refresh(&mut self.outside, now);
        self.on_clock_change(now);
        self.refresh(now);
    }

    /// The core went to sleep or woke up.
    pub(crate) fn account_sleep(&mut self, asleep: bool, now: u64) {
        if asleep {
            if self.asleep_since.is_none() {
                self.cpu.busy_ns += now.saturating_sub(self.awake_since);
                self.asleep_since = Some(now);
            }
        } else if let Some(since) = self.asleep_since.take() {
            self.cpu.asleep_ns += now.saturating_sub(since);
            self.awake_since = now;
        }
    }
}
