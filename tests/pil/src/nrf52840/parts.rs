//! The peripherals on the event bus, addressed by their 4 KiB slot: register dispatch,
//! stepping, interrupt lines and reset, in one place so the SoC can lend them the rest of
//! the chip (`Ctx`) while it owns the memories and the board.

use super::clock::{ClockFaults, ClockPower, Supply};
use super::events::Ctx;
use super::gpiote::Gpiote;
use super::map::{base, irq_of, slot};
use super::nvmc::{FlashTiming, Nvmc};
use super::ppi::Ppi;
use super::pwm::Pwm;
use super::rng::Rng;
use super::rtc::Rtc;
use super::saadc::Saadc;
use super::spim::Spim;
use super::temp::Temp;
use super::timer::Timer;
use super::uarte::Uarte;
use super::wdt::Wdt;

/// Every peripheral the model implements.
pub struct Parts {
    pub clock: ClockPower,
    pub nvmc: Nvmc,
    pub gpiote: Gpiote,
    pub ppi: Ppi,
    pub rtc: [Rtc; 3],
    pub timer: [Timer; 5],
    pub spim: [Spim; 4],
    pub uarte: [Uarte; 2],
    pub saadc: Saadc,
    pub wdt: Wdt,
    pub rng: Rng,
    pub pwm: Pwm,
    pub temp: Temp,
}

/// The bases of the RTCs, TIMERs, SPIMs and UARTEs, in instance order.
const RTCS: [u32; 3] = [base::RTC0, base::RTC1, base::RTC2];
const TIMERS: [u32; 5] = [
    base::TIMER0,
    base::TIMER1,
    base::TIMER2,
    base::TIMER3,
    base::TIMER4,
];
const SPIMS: [u32; 4] = [base::SPIM0, base::SPIM1, base::SPIM2, base::SPIM3];
const UARTES: [u32; 2] = [base::UARTE0, base::UARTE1];

fn instance(bases: &[u32], s: u32) -> Option<usize> {
    bases.iter().position(|&b| b == s)
}

impl Parts {
    /// Power-on state.
    pub fn new(
        faults: ClockFaults,
        supply: Supply,
        lf_ppm: f64,
        timing: FlashTiming,
        rng_seed: u64,
        corrupt_198: bool,
    ) -> Self {
        let clock = ClockPower::new(faults, supply, lf_ppm);
        let lf_period = clock.lf_period_fs();
        Self {
            clock,
            nvmc: Nvmc::new(timing),
            gpiote: Gpiote::new(),
            ppi: Ppi::new(),
            rtc: [
                Rtc::new(base::RTC0, 3),
                Rtc::new(base::RTC1, 4),
                Rtc::new(base::RTC2, 4),
            ],
            timer: [
                Timer::new(base::TIMER0, 4),
                Timer::new(base::TIMER1, 4),
                Timer::new(base::TIMER2, 4),
                Timer::new(base::TIMER3, 6),
                Timer::new(base::TIMER4, 6),
            ],
            spim: [
                Spim::new(0, base::SPIM0, corrupt_198),
                Spim::new(1, base::SPIM1, corrupt_198),
                Spim::new(2, base::SPIM2, corrupt_198),
                Spim::new(3, base::SPIM3, corrupt_198),
            ],
            uarte: [Uarte::new(0, base::UARTE0), Uarte::new(1, base::UARTE1)],
            saadc: Saadc::new(),
            wdt: Wdt::new(lf_period),
            rng: Rng::new(rng_seed),
            pwm: Pwm::new(),
            temp: Temp::new(),
        }
    }

    /// Whether a peripheral the model implements (NVMC aside) sits at this slot.
    pub fn owns(s: u32) -> bool {
        matches!(
            s,
            base::CLOCK_POWER
                | base::GPIOTE
                | base::PPI
                | base::SAADC
                | base::WDT
                | base::RNG
                | base::PWM0
                | base::TEMP
        ) || RTCS.contains(&s)
            || TIMERS.contains(&s)
            || SPIMS.contains(&s)
            || UARTES.contains(&s)
    }

    /// A register read at `addr`; `None` when not implemented.
    pub fn read(&self, addr: u32, now: u64) -> Option<u32> {
        let s = slot(addr);
        let off = addr & 0xFFC;
        match s {
            base::CLOCK_POWER => self.clock.read(off),
            base::GPIOTE => self.gpiote.read(off),
            base::PPI => self.ppi.read(off),
            base::SAADC => self.saadc.read(off),
            base::WDT => self.wdt.read(off),
            base::RNG => self.rng.read(off),
            base::PWM0 => self.pwm.read(off),
            base::TEMP => self.temp.read(off),
            _ => {
                if let Some(n) = instance(&RTCS, s) {
                    self.rtc.get(n)?.read(off, now)
                } else if let Some(n) = instance(&TIMERS, s) {
                    self.timer.get(n)?.read(off)
                } else if let Some(n) = instance(&SPIMS, s) {
                    self.spim.get(n)?.read(off)
                } else if let Some(n) = instance(&UARTES, s) {
                    self.uarte.get(n)?.read(off)
                } else {
                    None
                }
            }
        }
    }

    /// A register write at `addr` (tasks included); false when not implemented.
    pub fn write(&mut self, addr: u32, value: u32, ctx: &mut Ctx<'_>) -> bool {
        let s = slot(addr);
        let off = addr & 0xFFC;
        match s {
            base::CLOCK_POWER => {
                let done = self.clock.write(off, value, ctx);
                if off == 0xE00 {
                    ctx.ram.workaround_mask = value;
                }
                done
            }
            base::GPIOTE => self.gpiote.write(off, value, ctx),
            base::PPI => self.ppi.write(off, value),
            base::SAADC => self.saadc.write(off, value, ctx),
            base::WDT => self.wdt.write(off, value, ctx),
            base::RNG => self.rng.write(off, value, ctx.now),
            base::PWM0 => self.pwm.write(off, value, ctx),
            base::TEMP => self.temp.write(off, value),
            _ => {
                if let Some(r) = instance(&RTCS, s).and_then(|n| self.rtc.get_mut(n)) {
                    r.write(off, value, ctx)
                } else if let Some(t) = instance(&TIMERS, s).and_then(|n| self.timer.get_mut(n)) {
                    t.write(off, value, ctx)
                } else if let Some(p) = instance(&SPIMS, s).and_then(|n| self.spim.get_mut(n)) {
                    p.write(off, value, ctx)
                } else if let Some(u) = instance(&UARTES, s).and_then(|n| self.uarte.get_mut(n)) {
                    u.write(off, value, ctx)
                } else {
                    false
                }
            }
        }
    }

    /// The earliest time any of them changes state on its own.
    pub fn next_event_ns(&self) -> u64 {
        let mut next = self
            .clock
            .next_event_ns()
            .min(self.saadc.next_event_ns())
            .min(self.wdt.next_event_ns())
            .min(self.rng.next_event_ns())
            .min(self.pwm.next_event_ns());
        for r in &self.rtc {
            next = next.min(r.next_event_ns());
        }
        for t in &self.timer {
            next = next.min(t.next_event_ns());
        }
        for p in &self.spim {
            next = next.min(p.next_event_ns());
        }
        for u in &self.uarte {
            next = next.min(u.next_event_ns());
        }
        next
    }

    /// Lets every peripheral with something due at `ctx.now` act.
    pub fn step(&mut self, ctx: &mut Ctx<'_>) {
        let now = ctx.now;
        if self.clock.next_event_ns() <= now {
            self.clock.step(ctx);
        }
        for r in &mut self.rtc {
            if r.next_event_ns() <= now {
                r.step(ctx);
            }
        }
        for t in &mut self.timer {
            if t.next_event_ns() <= now {
                t.step(ctx);
            }
        }
        for p in &mut self.spim {
            if p.next_event_ns() <= now {
                p.step(ctx);
            }
        }
        for u in &mut self.uarte {
            if u.next_event_ns() <= now {
                u.step(ctx);
            }
        }
        if self.saadc.next_event_ns() <= now {
            self.saadc.step(ctx);
        }
        if self.wdt.next_event_ns() <= now {
            self.wdt.step(ctx);
        }
        if self.rng.next_event_ns() <= now {
            self.rng.step(ctx);
        }
        if self.pwm.next_event_ns() <= now {
            self.pwm.step(ctx);
        }
    }

    /// The interrupt request lines, one bit per IRQ number.
    pub fn irq_lines(&self) -> [u32; 8] {
        let mut lines = [0u32; 8];
        let mut set = |b: u32, on: bool| {
            let n = irq_of(b);
            if on && let Some(w) = lines.get_mut((n / 32) as usize) {
                *w |= 1 << (n % 32);
            }
        };
        set(base::CLOCK_POWER, self.clock.irq());
        set(base::GPIOTE, self.gpiote.irq());
        set(base::SAADC, self.saadc.irq());
        set(base::WDT, self.wdt.irq());
        set(base::RNG, self.rng.irq());
        set(base::PWM0, self.pwm.irq());
        for (r, &b) in self.rtc.iter().zip(&RTCS) {
            set(b, r.irq());
        }
        for (t, &b) in self.timer.iter().zip(&TIMERS) {
            set(b, t.irq());
        }
        for (p, &b) in self.spim.iter().zip(&SPIMS) {
            set(b, p.irq());
        }
        for (u, &b) in self.uarte.iter().zip(&UARTES) {
            set(b, u.irq());
        }
        lines
    }

    /// A reset of the peripherals (`watchdog_too` for watchdog and power-on resets).
    pub fn reset(&mut self, ctx: &mut Ctx<'_>, watchdog_too: bool) {
        self.nvmc.reset();
        self.gpiote.reset(ctx);
        self.ppi.reset();
        let lf = self.clock.lf_timing();
        for r in &mut self.rtc {
            r.reset();
            r.lf_changed(lf, ctx.now);
        }
        for t in &mut self.timer {
            t.reset();
        }
        for p in &mut self.spim {
            p.reset(ctx);
        }
        for u in &mut self.uarte {
            u.reset(ctx);
        }
        self.saadc.reset();
        if watchdog_too {
            self.wdt.reset();
        }
        self.rng.reset();
        self.pwm.reset(ctx);
        self.temp = Temp::new();
    }
}
