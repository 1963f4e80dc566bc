//! GPIOTE (PS "GPIOTE"): eight channels, each an event on a pin's edges (EVENTS_IN) or a
//! task-driven output (TASKS_OUT/SET/CLR), and the PORT event from DETECT.

use super::events::{Ctx, EventRegs};
use super::gpio::index;
use crate::wire::{Drive, Pin};

/// Channels.
const CHANNELS: usize = 8;
/// Event index of PORT (offset 0x17C).
const PORT: u32 = 31;
/// The owner name GPIOTE claims pins under.
const OWNER: &str = "GPIOTE";

/// CONFIG.MODE.
const MODE_EVENT: u32 = 1;
const MODE_TASK: u32 = 3;

/// GPIOTE.
pub struct Gpiote {
    ev: EventRegs,
    config: [u32; CHANNELS],
    out: [bool; CHANNELS],
}

fn pin_of(config: u32) -> Pin {
    Pin::new(((config >> 13) & 1) as u8, ((config >> 8) & 0x1F) as u8)
}

impl Gpiote {
    /// Reset state.
    pub const fn new() -> Self {
        Self {
            ev: EventRegs::new(super::map::base::GPIOTE),
            config: [0; CHANNELS],
            out: [false; CHANNELS],
        }
    }

    /// The interrupt line.
    pub const fn irq(&self) -> bool {
        self.ev.irq()
    }

    /// Pins watched by channels in event mode (bit = pin index).
    pub fn watch_mask(&self) -> u64 {
        self.config
            .iter()
            .filter(|&&c| c & 3 == MODE_EVENT)
            .filter_map(|&c| index(pin_of(c)))
            .fold(0, |m, i| m | (1 << i))
    }

    /// A watched pin changed level.
    pub fn on_edge(&mut self, pin_index: usize, rising: bool, fired: &mut Vec<u32>) {
        for (n, &c) in self.config.iter().enumerate() {
            if c & 3 != MODE_EVENT || index(pin_of(c)) != Some(pin_index) {
                continue;
            }
            let hit = match (c >> 16) & 3 {
                1 => rising,
                2 => !rising,
                3 => true,
                _ => false,
            };
            if hit {
                self.ev.raise(n as u32, fired);
            }
        }
    }

    /// DETECT rose.
    pub fn on_port(&mut self, fired: &mut Vec<u32>) {
        self.ev.raise(PORT, fired);
    }

    fn drive(&mut self, n: usize, level: bool, ctx: &mut Ctx<'_>) {
        let Some(&c) = self.config.get(n) else {
            return;
        };
        if c & 3 != MODE_TASK {
            return;
        }
        if let Some(o) = self.out.get_mut(n) {
            *o = level;
        }
        let drive = if level { Drive::High } else { Drive::Low };
        ctx.pins
            .claim(pin_of(c), OWNER, drive, ctx.outside, ctx.now);
    }

    /// A register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        if let Some(v) = self.ev.read(offset) {
            return Some(v);
        }
        match offset {
            0x510..0x530 => self.config.get(((offset - 0x510) / 4) as usize).copied(),
            _ => None,
        }
    }

    /// A register write (tasks included); false if not implemented.
    pub fn write(&mut self, offset: u32, value: u32, ctx: &mut Ctx<'_>) -> bool {
        if self.ev.write(offset, value) {
            return true;
        }
        let n = (offset % 0x30 / 4) as usize;
        match offset {
            0x000..0x020 if value & 1 != 0 => {
                let level = !self.out.get(n).copied().unwrap_or(false);
                let polarity = self.config.get(n).map_or(0, |c| (c >> 16) & 3);
                let level = match polarity {
                    1 => true,
                    2 => false,
                    3 => level,
                    _ => return true,
                };
                self.drive(n, level, ctx);
            }
            0x030..0x050 if value & 1 != 0 => self.drive(n, true, ctx),
            0x060..0x080 if value & 1 != 0 => self.drive(n, false, ctx),
            0x000..0x080 => {}
            0x510..0x530 => {
                let n = ((offset - 0x510) / 4) as usize;
                let old = self.config.get(n).copied().unwrap_or(0);
                if old & 3 == MODE_TASK {
                    ctx.pins.release(pin_of(old), OWNER, ctx.outside, ctx.now);
                }
                if let Some(c) = self.config.get_mut(n) {
                    *c = value & 0x0013_3F03;
                }
                if value & 3 == MODE_TASK {
                    let level = value & (1 << 20) != 0;
                    self.drive(n, level, ctx);
                }
            }
            _ => return false,
        }
        true
    }

    /// Reset: channels disabled (the pins they held go back to GPIO).
    pub fn reset(&mut self, ctx: &mut Ctx<'_>) {
        for &c in &self.config {
            if c & 3 == MODE_TASK {
                ctx.pins.release(pin_of(c), OWNER, ctx.outside, ctx.now);
            }
        }
        *self = Self::new();
    }
}
