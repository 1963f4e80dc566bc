//! What every nRF52 peripheral shares (PS "Peripheral interface"): event registers at
//! 0x100 + 4·n that the peripheral sets and software clears, interrupt enables where bit n
//! belongs to the event at 0x100 + 4·n (INTEN/INTENSET/INTENCLR at 0x300/0x304/0x308), one
//! interrupt line per peripheral that is high while any enabled event is set, SHORTS at
//! 0x200, and the context a peripheral acts in (time, board, RAM, pins, PPI outbox).

use super::gpio::Pins;
use super::memory::Ram;
use super::records::Records;
use crate::wire::Outside;

/// First event register offset.
pub const EVENTS: u32 = 0x100;
/// Past the last event register whose interrupt enable bit exists (32 events).
pub const EVENTS_END: u32 = 0x180;
/// SHORTS offset.
pub const SHORTS: u32 = 0x200;
/// INTEN offset.
pub const INTEN: u32 = 0x300;
/// INTENSET offset.
pub const INTENSET: u32 = 0x304;
/// INTENCLR offset.
pub const INTENCLR: u32 = 0x308;

/// The event index of an event register offset.
pub const fn event(offset: u32) -> u32 {
    (offset - EVENTS) / 4
}

/// A peripheral's event registers, interrupt enables and shortcuts.
#[derive(Clone, Debug)]
pub struct EventRegs {
    base: u32,
    events: u32,
    inten: u32,
    /// The SHORTS register (each peripheral gives its bits their meaning).
    pub shorts: u32,
}

impl EventRegs {
    /// All clear, for the peripheral at `base`.
    pub const fn new(base: u32) -> Self {
        Self {
            base,
            events: 0,
            inten: 0,
            shorts: 0,
        }
    }

    /// The peripheral's base address.
    pub const fn base(&self) -> u32 {
        self.base
    }

    /// The peripheral generates event `index`: the register is set and the event goes out
    /// to the PPI (`fired`).
    pub fn raise(&mut self, index: u32, fired: &mut Vec<u32>) {
        self.events |= 1 << (index & 31);
        fired.push(self.base + EVENTS + 4 * index);
    }

    /// Sets the register of event `index` without reporting it to the PPI (the RTC's events
    /// whose EVTEN bit is clear).
    pub fn set_quietly(&mut self, index: u32) {
        self.events |= 1 << (index & 31);
    }

    /// Whether shortcut bit `bit` is enabled.
    pub const fn short(&self, bit: u32) -> bool {
        self.shorts & (1 << (bit & 31)) != 0
    }

    /// Whether interrupt enable bit `bit` is set.
    pub const fn enabled(&self, bit: u32) -> bool {
        self.inten & (1 << (bit & 31)) != 0
    }

    /// The peripheral's interrupt line: any enabled event set.
    pub const fn irq(&self) -> bool {
        self.events & self.inten != 0
    }

    /// Reads a common register; `None` for offsets this block does not own.
    pub const fn read(&self, offset: u32) -> Option<u32> {
        match offset {
            EVENTS..EVENTS_END if offset.is_multiple_of(4) => {
                Some((self.events >> event(offset)) & 1)
            }
            SHORTS => Some(self.shorts),
            INTEN | INTENSET | INTENCLR => Some(self.inten),
            _ => None,
        }
    }

    /// Writes a common register; false for offsets this block does not own. Software may
    /// set an event register too (it raises the interrupt, not a PPI event).
    pub fn write(&mut self, offset: u32, value: u32) -> bool {
        match offset {
            EVENTS..EVENTS_END if offset.is_multiple_of(4) => {
                let bit = 1 << event(offset);
                if value & 1 != 0 {
                    self.events |= bit;
                } else {
                    self.events &= !bit;
                }
            }
            SHORTS => self.shorts = value,
            INTEN => self.inten = value,
            INTENSET => self.inten |= value,
            INTENCLR => self.inten &= !value,
            _ => return false,
        }
        true
    }

    /// Back to the reset state.
    pub fn reset(&mut self) {
        *self = Self::new(self.base);
    }
}

/// Where a peripheral acts: the time, the board, RAM (EasyDMA), the pins, and the outbox of
/// events it generates for the PPI.
pub struct Ctx<'a> {
    /// Virtual time of the action, ns since power-on.
    pub now: u64,
    /// The board.
    pub outside: &'a mut dyn Outside,
    /// RAM as EasyDMA reaches it.
    pub ram: &'a mut Ram,
    /// GPIO pins, for peripherals that take or watch them.
    pub pins: &'a mut Pins,
    /// Event register addresses generated, in order, for the PPI.
    pub fired: &'a mut Vec<u32>,
    /// What the run records for the runner (DMA faults, notes).
    pub records: &'a mut Records,
}

/// A time in ns `cycles` periods of `period_ps` after `origin`, rounded up to the next ns
/// (a hardware edge is never earlier than its count says).
pub const fn after_ps(origin: u64, cycles: u64, period_ps: u64) -> u64 {
    let ps = cycles as u128 * period_ps as u128;
    origin.saturating_add(ps.div_ceil(1000) as u64)
}
