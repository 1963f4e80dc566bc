//! TIMER0–4 (PS "TIMER"): a counter of 8/16/24/32 bits at 16 MHz / 2^PRESCALER in timer
//! mode or on COUNT tasks in counter mode, CC registers with COMPARE events, CAPTURE,
//! START/STOP/CLEAR, and the COMPARE→CLEAR/STOP shortcuts. The PPM input captures edges
//! with it (GPIOTE → PPI → CAPTURE) and the UARTEs' idle-line detection times gaps with it.

use super::events::{Ctx, EventRegs, after_ps};

/// Event index of COMPARE[0] (offset 0x140).
const COMPARE0: u32 = 16;
/// One 16 MHz period, ps.
const PCLK16M_PS: u64 = 62_500;

/// One TIMER instance.
pub struct Timer {
    ev: EventRegs,
    ccs: usize,
    cc: [u32; 6],
    mode: u32,
    bitmode: u32,
    prescaler: u32,
    running: bool,
    /// The counter when the current stretch began.
    base: u32,
    /// When the current stretch began (tick 0).
    start_ns: u64,
    /// Ticks of the stretch whose events have been generated.
    processed: u64,
}

impl Timer {
    /// An instance at `base` with `ccs` CC registers.
    pub const fn new(base: u32, ccs: usize) -> Self {
        Self {
            ev: EventRegs::new(base),
            ccs,
            cc: [0; 6],
            mode: 0,
            bitmode: 0,
            prescaler: 4,
            running: false,
            base: 0,
            start_ns: 0,
            processed: 0,
        }
    }

    /// The interrupt line.
    pub const fn irq(&self) -> bool {
        self.ev.irq()
    }

    const fn mask(&self) -> u32 {
        match self.bitmode & 3 {
            0 => 0xFFFF,
            1 => 0xFF,
            2 => 0xFF_FFFF,
            _ => 0xFFFF_FFFF,
        }
    }

    const fn timer_mode(&self) -> bool {
        self.mode & 3 == 0
    }

    fn period_ps(&self) -> u64 {
        PCLK16M_PS << self.prescaler.min(9)
    }

    fn ticks(&self, t: u64) -> u64 {
        if !self.running || !self.timer_mode() {
            return 0;
        }
        let ps = u128::from(t.saturating_sub(self.start_ns)) * 1000;
        (ps / u128::from(self.period_ps())) as u64
    }

    /// The counter at `t`.
    pub fn counter(&self, t: u64) -> u32 {
        self.base.wrapping_add(self.ticks(t) as u32) & self.mask()
    }

    fn rebase(&mut self, now: u64, value: u32) {
        self.base = value & self.mask();
        self.start_ns = now;
        self.processed = 0;
    }

    /// The next tick of this stretch at which a CC matches.
    fn next_match(&self) -> Option<u64> {
        if !self.running || !self.timer_mode() {
            return None;
        }
        let span = u64::from(self.mask()) + 1;
        let now = self.base.wrapping_add(self.processed as u32) & self.mask();
        self.cc
            .iter()
            .take(self.ccs)
            .map(|&c| {
                let d = u64::from(c.wrapping_sub(now) & self.mask());
                self.processed + if d == 0 { span } else { d }
            })
            .min()
    }

    /// When the next COMPARE is due.
    pub fn next_event_ns(&self) -> u64 {
        self.next_match()
            .map_or(u64::MAX, |k| after_ps(self.start_ns, k, self.period_ps()))
    }

    /// Raises COMPARE for every CC equal to `value`, with its shortcuts.
    fn compare(&mut self, value: u32, at: u64, fired: &mut Vec<u32>) {
        let (mut clear, mut stop) = (false, false);
        for n in 0..self.ccs {
            if self.cc.get(n) == Some(&value) {
                self.ev.raise(COMPARE0 + n as u32, fired);
                clear |= self.ev.short(n as u32);
                stop |= self.ev.short(n as u32 + 8);
            }
        }
        if stop {
            self.running = false;
            self.rebase(at, value);
        }
        if clear {
            self.rebase(at, 0);
        }
    }

    /// Generates the COMPARE events due at `ctx.now`.
    pub fn step(&mut self, ctx: &mut Ctx<'_>) {
        while let Some(k) = self.next_match() {
            let at = after_ps(self.start_ns, k, self.period_ps());
            if at > ctx.now {
                break;
            }
            self.processed = k;
            let value = self.base.wrapping_add(k as u32) & self.mask();
            self.compare(value, at, ctx.fired);
        }
    }

    /// A register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        if let Some(v) = self.ev.read(offset) {
            return Some(v);
        }
        Some(match offset {
            0x504 => self.mode,
            0x508 => self.bitmode,
            0x510 => self.prescaler,
            0x540..0x558 => {
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
        if self.ev.write(offset, value) {
            return true;
        }
        let now = ctx.now;
        // Every tick up to now has had its events (the SoC catches up before an access).
        self.processed = self.processed.max(self.ticks(now));
        let task = value & 1 != 0;
        match offset {
            0x000 if task && !self.running => {
                let value = self.counter(now);
                self.running = true;
                self.rebase(now, value);
            }
            0x004 | 0x010 if task => {
                let value = self.counter(now);
                self.running = false;
                self.rebase(now, value);
            }
            0x008 if task && !self.timer_mode() => {
                let value = self.base.wrapping_add(1) & self.mask();
                self.rebase(now, value);
                self.compare(value, now, ctx.fired);
            }
            0x00C if task => self.rebase(now, 0),
            0x000..=0x010 => {}
            0x040..0x058 if task => {
                let n = ((offset - 0x040) / 4) as usize;
                if n >= self.ccs {
                    return false;
                }
                let value = self.counter(now);
                if let Some(c) = self.cc.get_mut(n) {
                    *c = value;
                }
            }
            0x040..0x058 => {}
            0x504 => self.mode = value & 3,
            0x508 => {
                let value_now = self.counter(now);
                self.bitmode = value & 3;
                self.rebase(now, value_now);
            }
            0x510 => {
                let value_now = self.counter(now);
                self.prescaler = value & 0xF;
                self.rebase(now, value_now);
            }
            0x540..0x558 => {
                let n = ((offset - 0x540) / 4) as usize;
                if n >= self.ccs {
                    return false;
                }
                if let Some(c) = self.cc.get_mut(n) {
                    *c = value;
                }
            }
            _ => return false,
        }
        true
    }

    /// Reset state.
    pub fn reset(&mut self) {
        *self = Self::new(self.ev.base(), self.ccs);
    }
}
