//! RTC0–2 (PS "RTC"): a 24-bit COUNTER that advances every PRESCALER + 1 ticks of the
//! LFCLK while started (and only while the LFCLK runs), compare registers, TICK, OVRFLW
//! and COMPARE events, EVTEN for routing them to the PPI, TRIGOVRFLW.
//!
//! A COMPARE event comes when COUNTER advances to CC[n]; writing CC[n] equal to the
//! current COUNTER gives no event until the counter comes round again (the PS: writing N
//! or N + 1 "may not" trigger; embassy-time's driver keeps 3 ticks of margin). TICK events
//! are only generated while their interrupt or EVTEN bit is on (nothing else observes them).

use super::clock::LfTiming;
use super::events::{Ctx, EventRegs};

const MASK: u32 = 0x00FF_FFFF;
const WRAP: u64 = 1 << 24;

/// Event indices.
const TICK: u32 = 0;
const OVRFLW: u32 = 1;
const COMPARE0: u32 = 16;

/// One RTC instance.
pub struct Rtc {
    ev: EventRegs,
    ccs: usize,
    cc: [u32; 4],
    evten: u32,
    prescaler: u32,
    started: bool,
    lf: Option<LfTiming>,
    /// COUNTER when the current counting stretch began.
    base: u32,
    /// The LF tick the stretch began at, while counting.
    anchor: Option<u64>,
    /// Increments of this stretch whose events have been generated.
    processed: u64,
}

impl Rtc {
    /// An instance at `base` with `ccs` compare registers.
    pub const fn new(base: u32, ccs: usize) -> Self {
        Self {
            ev: EventRegs::new(base),
            ccs,
            cc: [0; 4],
            evten: 0,
            prescaler: 0,
            started: false,
            lf: None,
            base: 0,
            anchor: None,
            processed: 0,
        }
    }

    /// The interrupt line.
    pub const fn irq(&self) -> bool {
        self.ev.irq()
    }

    fn divider(&self) -> u64 {
        u64::from(self.prescaler) + 1
    }

    fn increments(&self, t: u64) -> u64 {
        match (self.anchor, self.lf) {
            (Some(a), Some(lf)) => lf.ticks_at(t).saturating_sub(a) / self.divider(),
            _ => 0,
        }
    }

    /// COUNTER at `t`.
    pub fn counter(&self, t: u64) -> u32 {
        (self.base.wrapping_add(self.increments(t) as u32)) & MASK
    }

    /// Restarts the bookkeeping at `now` with COUNTER = `value`.
    fn rebase(&mut self, now: u64, value: u32) {
        self.base = value & MASK;
        self.processed = 0;
        self.anchor = match self.lf {
            Some(lf) if self.started => Some(lf.ticks_at(now)),
            _ => None,
        };
    }

    /// The LFCLK started or stopped.
    pub fn lf_changed(&mut self, lf: Option<LfTiming>, now: u64) {
        let value = self.counter(now);
        self.lf = lf;
        self.rebase(now, value);
    }

    fn wants_tick(&self) -> bool {
        (self.ev.enabled(TICK) || self.evten & 1 != 0) && self.anchor.is_some()
    }

    /// The next increment (of this stretch) that generates an event.
    fn next_increment(&self) -> Option<u64> {
        self.anchor?;
        let at = |value: u32| {
            let now = self.base.wrapping_add(self.processed as u32) & MASK;
            let d = u64::from(value.wrapping_sub(now) & MASK);
            self.processed + if d == 0 { WRAP } else { d }
        };
        let mut next = at(0);
        for &c in self.cc.iter().take(self.ccs) {
            next = next.min(at(c));
        }
        if self.wants_tick() {
            next = next.min(self.processed + 1);
        }
        Some(next)
    }

    fn time_of(&self, increment: u64) -> u64 {
        match (self.anchor, self.lf) {
            (Some(a), Some(lf)) => lf.tick_time(a + increment * self.divider()),
            _ => u64::MAX,
        }
    }

    /// When the next event is due.
    pub fn next_event_ns(&self) -> u64 {
        self.next_increment().map_or(u64::MAX, |i| self.time_of(i))
    }

    fn generate(&mut self, index: u32, fired: &mut Vec<u32>) {
        if self.evten & (1 << index) != 0 {
            self.ev.raise(index, fired);
        } else {
            self.ev.set_quietly(index);
        }
    }

    /// Generates the events due at `ctx.now`.
    pub fn step(&mut self, ctx: &mut Ctx<'_>) {
        while let Some(inc) = self.next_increment() {
            if self.time_of(inc) > ctx.now {
                break;
            }
            self.processed = inc;
            let value = self.base.wrapping_add(inc as u32) & MASK;
            if self.wants_tick() {
                self.generate(TICK, ctx.fired);
            }
            if value == 0 {
                self.generate(OVRFLW, ctx.fired);
            }
            for n in 0..self.ccs {
                if self.cc.get(n) == Some(&value) {
                    self.generate(COMPARE0 + n as u32, ctx.fired);
                }
            }
        }
    }

    /// A register read.
    pub fn read(&self, offset: u32, now: u64) -> Option<u32> {
        if let Some(v) = self.ev.read(offset) {
            return Some(v);
        }
        Some(match offset {
            0x340..=0x348 => self.evten,
            0x504 => self.counter(now),
            0x508 => self.prescaler,
            0x540..0x550 => {
                let n = ((offset - 0x540) / 4) as usize;
                if n >= self.ccs {
                    return None;
                }
                *self.cc.get(n)?
            }
            _ => return None,
        })
    }

    /// A register write (tasks included); false if not implemented.
    pub fn write(&mut self, offset: u32, value: u32, ctx: &mut Ctx<'_>) -> bool {
        let now = ctx.now;
        if self.ev.write(offset, value) {
            return true;
        }
        // Every increment up to now has had its events (the SoC catches up first).
        self.processed = self.processed.max(self.increments(now));
        let task = value & 1 != 0;
        match offset {
            0x000 if task => {
                let value = self.counter(now);
                self.started = true;
                self.rebase(now, value);
            }
            0x004 if task => {
                let value = self.counter(now);
                self.started = false;
                self.rebase(now, value);
            }
            0x008 if task => self.rebase(now, 0),
            0x00C if task => self.rebase(now, 0xFF_FFF0),
            0x000..=0x00C => {}
            0x340 => self.evten = value,
            0x344 => self.evten |= value,
            0x348 => self.evten &= !value,
            // PRESCALER is only writable while stopped (PS "RTC": PRESCALER).
            0x508 if !self.started => self.prescaler = value & 0xFFF,
            0x508 => ctx
                .records
                .note("RTC", "PRESCALER written while running (ignored)", now),
            0x540..0x550 => {
                let n = ((offset - 0x540) / 4) as usize;
                if n >= self.ccs {
                    return false;
                }
                if let Some(c) = self.cc.get_mut(n) {
                    *c = value & MASK;
                }
            }
            _ => return false,
        }
        true
    }

    /// Reset (the LFCLK's state is the clock's, kept).
    pub fn reset(&mut self) {
        let lf = self.lf;
        *self = Self::new(self.ev.base(), self.ccs);
        self.lf = lf;
    }
}
