//! RNG (PS "RNG"): started, it produces a byte in VALUE every t_RNG and raises VALRDY;
//! VALRDY→STOP shortcut; bias correction (CONFIG.DERCEN) makes it slower. The bytes come
//! from the project's seeded SplitMix64 (`sim-rng`), so a run is reproducible from its seed.
//! Byte times (PS "RNG electrical specification"): 30 µs typical without bias correction,
//! 120 µs with it.

use sim_rng::SplitMix64;

use super::events::{Ctx, EventRegs};

/// Time per byte without bias correction, ns.
const BYTE_NS: u64 = 30_000;
/// Time per byte with bias correction, ns.
const BYTE_CORRECTED_NS: u64 = 120_000;
/// Event index of VALRDY; SHORTS bit VALRDY→STOP.
const VALRDY: u32 = 0;
const VALRDY_STOP: u32 = 0;

/// The RNG.
pub struct Rng {
    ev: EventRegs,
    source: SplitMix64,
    config: u32,
    value: u32,
    next: Option<u64>,
}

impl Rng {
    /// Reset state drawing from `seed`.
    pub fn new(seed: u64) -> Self {
        Self {
            ev: EventRegs::new(super::map::base::RNG),
            source: SplitMix64::new(seed),
            config: 0,
            value: 0,
            next: None,
        }
    }

    /// The interrupt line.
    pub const fn irq(&self) -> bool {
        self.ev.irq()
    }

    fn byte_ns(&self) -> u64 {
        if self.config & 1 != 0 {
            BYTE_CORRECTED_NS
        } else {
            BYTE_NS
        }
    }

    /// When the next byte is ready.
    pub fn next_event_ns(&self) -> u64 {
        self.next.unwrap_or(u64::MAX)
    }

    /// Produces the byte due at `ctx.now`.
    pub fn step(&mut self, ctx: &mut Ctx<'_>) {
        let Some(at) = self.next else {
            return;
        };
        if at > ctx.now {
            return;
        }
        self.value = (self.source.next_u64() & 0xFF) as u32;
        self.ev.raise(VALRDY, ctx.fired);
        self.next = if self.ev.short(VALRDY_STOP) {
            None
        } else {
            Some(at + self.byte_ns())
        };
    }

    /// A register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        if let Some(v) = self.ev.read(offset) {
            return Some(v);
        }
        match offset {
            0x504 => Some(self.config),
            0x508 => Some(self.value),
            _ => None,
        }
    }

    /// A register write (tasks included); false if not implemented.
    pub fn write(&mut self, offset: u32, value: u32, now: u64) -> bool {
        if self.ev.write(offset, value) {
            return true;
        }
        match offset {
            0x000 if value & 1 != 0 && self.next.is_none() => {
                self.next = Some(now + self.byte_ns())
            }
            0x004 if value & 1 != 0 => self.next = None,
            0x000 | 0x004 => {}
            0x504 => self.config = value & 1,
            _ => return false,
        }
        true
    }

    /// Reset state; the random stream goes on (it is the chip's noise, not a register).
    pub fn reset(&mut self) {
        self.ev.reset();
        self.config = 0;
        self.value = 0;
        self.next = None;
    }
}
