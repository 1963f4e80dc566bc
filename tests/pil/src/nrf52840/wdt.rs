//! WDT (PS "WDT"): counts CRV + 1 ticks of the 32.768 kHz clock from TASKS_START; RR[n]
//! written with 0x6E524635 marks reload request n done (REQSTATUS), and when every request
//! enabled in RREN is done the counter reloads. CRV, RREN and CONFIG are locked once it
//! runs. At expiry TIMEOUT is raised and the chip resets — two 32.768 kHz cycles later when
//! the TIMEOUT interrupt is enabled (PS: the reset is postponed so the handler can run).
//! CONFIG.SLEEP clear pauses it while the CPU sleeps. It is reset only by its own reset and
//! power-on: it keeps running through a soft reset (PS "Reset behavior"). CONFIG.HALT
//! (debugger halt) has nothing to act on here.

use super::events::{Ctx, EventRegs};

/// The reload key.
pub const RELOAD: u32 = 0x6E52_4635;
/// Event index of TIMEOUT.
const TIMEOUT: u32 = 0;

/// The watchdog.
pub struct Wdt {
    ev: EventRegs,
    period_fs: u64,
    crv: u32,
    rren: u32,
    config: u32,
    running: bool,
    reqstatus: u32,
    /// When it expires, while it counts.
    expiry: Option<u64>,
    /// Counting time left while paused in sleep.
    paused: Option<u64>,
    /// The reset after TIMEOUT.
    reset_at: Option<u64>,
    reset_pending: bool,
    /// Expiries since power-on.
    pub timeouts: u64,
}

impl Wdt {
    /// Reset state; it counts the LFCLK at `period_fs` femtoseconds a tick.
    pub const fn new(period_fs: u64) -> Self {
        Self {
            ev: EventRegs::new(super::map::base::WDT),
            period_fs,
            crv: 0xFFFF_FFFF,
            rren: 1,
            config: 1,
            running: false,
            reqstatus: 0,
            expiry: None,
            paused: None,
            reset_at: None,
            reset_pending: false,
            timeouts: 0,
        }
    }

    /// The interrupt line.
    pub const fn irq(&self) -> bool {
        self.ev.irq()
    }

    /// `ticks` of the 32.768 kHz clock, ns (rounded up).
    fn ticks_ns(&self, ticks: u64) -> u64 {
        (u128::from(ticks) * u128::from(self.period_fs)).div_ceil(1_000_000) as u64
    }

    fn timeout_ns(&self) -> u64 {
        self.ticks_ns(u64::from(self.crv) + 1)
    }

    /// The expiry or the reset after it.
    pub fn next_event_ns(&self) -> u64 {
        self.expiry
            .unwrap_or(u64::MAX)
            .min(self.reset_at.unwrap_or(u64::MAX))
    }

    /// Takes the reset request the expiry made.
    pub fn take_reset(&mut self) -> bool {
        core::mem::take(&mut self.reset_pending)
    }

    /// Expires or resets at `ctx.now`.
    pub fn step(&mut self, ctx: &mut Ctx<'_>) {
        if let Some(at) = self.reset_at
            && at <= ctx.now
        {
            self.reset_at = None;
            self.reset_pending = true;
        }
        if let Some(at) = self.expiry
            && at <= ctx.now
        {
            self.expiry = None;
            self.timeouts += 1;
            self.ev.raise(TIMEOUT, ctx.fired);
            if self.ev.enabled(TIMEOUT) {
                self.reset_at = Some(at + self.ticks_ns(2));
            } else {
                self.reset_pending = true;
            }
        }
    }

    /// The CPU went to sleep or woke up.
    pub fn sleeping(&mut self, asleep: bool, now: u64) {
        if !self.running || self.config & 1 != 0 {
            return;
        }
        if asleep {
            if let Some(at) = self.expiry.take() {
                self.paused = Some(at.saturating_sub(now));
            }
        } else if let Some(left) = self.paused.take() {
            self.expiry = Some(now + left);
        }
    }

    /// A register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        if let Some(v) = self.ev.read(offset) {
            return Some(v);
        }
        Some(match offset {
            0x400 => u32::from(self.running),
            0x404 => self.reqstatus,
            0x504 => self.crv,
            0x508 => self.rren,
            0x50C => self.config,
            _ => return None,
        })
    }

    /// A register write (tasks included); false if not implemented.
    pub fn write(&mut self, offset: u32, value: u32, ctx: &mut Ctx<'_>) -> bool {
        if self.ev.write(offset, value) {
            return true;
        }
        let now = ctx.now;
        match offset {
            0x000 if value & 1 != 0 && !self.running => {
                self.running = true;
                self.reqstatus = self.rren;
                self.expiry = Some(now + self.timeout_ns());
            }
            0x000 => {}
            0x504 | 0x508 | 0x50C if self.running => {
                ctx.records
                    .note("WDT", "configuration written while running (ignored)", now)
            }
            0x504 => self.crv = value.max(0xF),
            0x508 => self.rren = value & 0xFF,
            0x50C => self.config = value & 0x9,
            0x600..0x620 => {
                let n = (offset - 0x600) / 4;
                if self.running && value == RELOAD && self.rren & (1 << n) != 0 {
                    self.reqstatus &= !(1 << n);
                    if self.reqstatus & self.rren == 0 {
                        self.reqstatus = self.rren;
                        if self.expiry.is_some() {
                            self.expiry = Some(now + self.timeout_ns());
                        } else if self.paused.is_some() {
                            self.paused = Some(self.timeout_ns());
                        }
                    }
                }
            }
            _ => return false,
        }
        true
    }

    /// A watchdog or power-on reset stops it; other resets leave it counting.
    pub fn reset(&mut self) {
        let (period, timeouts) = (self.period_fs, self.timeouts);
        *self = Self::new(period);
        self.timeouts = timeouts;
    }
}
