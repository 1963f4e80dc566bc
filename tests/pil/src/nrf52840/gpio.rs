//! GPIO ports P0 (32 pins) and P1 (P1.00–P1.15) (PS "GPIO"): OUT/OUTSET/OUTCLR, IN,
//! DIR/DIRSET/DIRCLR, PIN_CNF with direction, input buffer, pull, drive and sense, LATCH and
//! DETECTMODE; peripherals that take a pin over (UARTE TXD, SPIM SCK/MOSI, PWM, GPIOTE
//! tasks); and the input side.
//!
//! The level of an input is, in order: the board's answer to `Outside::pin_level` now;
//! else the last level the board queued with `drive_input` whose time has come; else the
//! pin's own pull; else low (a floating input, noted). A pin the chip drives reads back its
//! own output. The board hears of every change of how a pin is driven (`pin_driven`).
//! Sense: LATCH bit n is set while pin n meets its SENSE condition; DETECT is the OR of the
//! conditions (DETECTMODE Default) or of LATCH (LDetect), and a rising DETECT of either port
//! is GPIOTE's PORT event. In LDetect mode, clearing LATCH while a bit stays set gives DETECT
//! a new rising edge.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::map::P1_PINS;
use crate::wire::{Drive, Outside, Pin, Pull};

/// Pins on the chip: P0.00–P0.31, then P1.00–P1.15.
pub const PIN_COUNT: usize = 32 + P1_PINS as usize;

/// PIN_CNF reset value: input, buffer disconnected, no pull.
const CNF_RESET: u32 = 0x2;

/// The index of a pin in [`Pins`].
pub const fn index(pin: Pin) -> Option<usize> {
    match pin.port {
        0 if pin.pin < 32 => Some(pin.pin as usize),
        1 if pin.pin < P1_PINS => Some(32 + pin.pin as usize),
        _ => None,
    }
}

/// The pin at an index.
const fn pin_at(i: usize) -> Pin {
    if i < 32 {
        Pin::new(0, i as u8)
    } else {
        Pin::new(1, (i - 32) as u8)
    }
}

#[derive(Clone, Copy, Debug)]
struct PinState {
    cnf: u32,
    out: bool,
    owner: Option<(&'static str, Drive)>,
    external: Option<bool>,
    last_level: Option<bool>,
    reported: Drive,
    latch: bool,
}

const PIN_RESET: PinState = PinState {
    cnf: CNF_RESET,
    out: false,
    owner: None,
    external: None,
    last_level: None,
    reported: Drive::Released(Pull::None),
    latch: false,
};

/// What settling the inputs produced.
#[derive(Debug, Default)]
pub struct Settled {
    /// Watched pins whose level changed: (pin index, new level).
    pub edges: Vec<(usize, bool)>,
    /// DETECT rose: GPIOTE's PORT event.
    pub port_event: bool,
}

/// Both ports' pins and registers.
pub struct Pins {
    pins: [PinState; PIN_COUNT],
    detectmode: [u32; 2],
    detect: bool,
    /// Pins GPIOTE watches in event mode (bit = pin index).
    pub gpiote_watch: u64,
    /// P0.09/P0.10 are the NFC antenna pads (UICR.NFCPINS.PROTECT at the last reset).
    pub nfc_pads: bool,
    queue: BinaryHeap<Reverse<(u64, u64, usize, bool)>>,
    queued: u64,
    /// Reads of an input nothing drives and no pull holds.
    pub floating_reads: u64,
}

impl Default for Pins {
    fn default() -> Self {
        Self::new()
    }
}

impl Pins {
    /// Reset state.
    pub fn new() -> Self {
        Self {
            pins: [PIN_RESET; PIN_COUNT],
            detectmode: [0; 2],
            detect: false,
            gpiote_watch: 0,
            nfc_pads: true,
            queue: BinaryHeap::new(),
            queued: 0,
            floating_reads: 0,
        }
    }

    fn effective(&self, i: usize) -> Drive {
        let Some(p) = self.pins.get(i) else {
            return Drive::Released(Pull::None);
        };
        if self.nfc_pads && (i == 9 || i == 10) {
            return Drive::Released(Pull::None);
        }
        if let Some((_, drive)) = p.owner {
            return drive;
        }
        let pull = match (p.cnf >> 2) & 3 {
            1 => Pull::Down,
            3 => Pull::Up,
            _ => Pull::None,
        };
        if p.cnf & 1 == 0 {
            return Drive::Released(pull);
        }
        let drive = (p.cnf >> 8) & 7;
        match (p.out, drive) {
            (true, 6 | 7) | (false, 4 | 5) => Drive::Released(pull),
            (true, _) => Drive::High,
            (false, _) => Drive::Low,
        }
    }

    /// Tells the board if pin `i`'s drive changed.
    fn refresh(&mut self, i: usize, outside: &mut dyn Outside, now: u64) {
        let drive = self.effective(i);
        if let Some(p) = self.pins.get_mut(i)
            && p.reported != drive
        {
            p.reported = drive;
            outside.pin_driven(pin_at(i), drive, now);
        }
    }

    /// The level on pin `i` now.
    pub fn level(&mut self, i: usize, outside: &mut dyn Outside, now: u64) -> bool {
        match self.effective(i) {
            Drive::High => true,
            Drive::Low => false,
            Drive::Released(pull) => {
                if let Some(level) = outside.pin_level(pin_at(i), now) {
                    return level;
                }
                if let Some(level) = self.pins.get(i).and_then(|p| p.external) {
                    return level;
                }
                match pull {
                    Pull::Up => true,
                    Pull::Down => false,
                    Pull::None => {
                        self.floating_reads += 1;
                        false
                    }
                }
            }
        }
    }

    /// A peripheral takes pin `pin` and drives it so.
    pub fn claim(
        &mut self,
        pin: Pin,
        owner: &'static str,
        drive: Drive,
        outside: &mut dyn Outside,
        now: u64,
    ) {
        if let Some(i) = index(pin) {
            if let Some(p) = self.pins.get_mut(i) {
                p.owner = Some((owner, drive));
            }
            self.refresh(i, outside, now);
        }
    }

    /// A peripheral gives pin `pin` back to GPIO (if it holds it).
    pub fn release(&mut self, pin: Pin, owner: &'static str, outside: &mut dyn Outside, now: u64) {
        if let Some(i) = index(pin) {
            if let Some(p) = self.pins.get_mut(i)
                && p.owner.is_some_and(|(o, _)| o == owner)
            {
                p.owner = None;
            }
            self.refresh(i, outside, now);
        }
    }

    /// The board queues a level on an input pin from `at_ns` on.
    pub fn drive_input(&mut self, pin: Pin, level: bool, at_ns: u64) {
        if let Some(i) = index(pin) {
            self.queued += 1;
            self.queue.push(Reverse((at_ns, self.queued, i, level)));
        }
    }

    /// The next queued input change.
    pub fn next_input_ns(&self) -> u64 {
        self.queue.peek().map_or(u64::MAX, |Reverse((t, ..))| *t)
    }

    /// Applies the queued inputs due at `now`.
    pub fn apply_inputs(&mut self, now: u64) {
        while let Some(Reverse((t, _, i, level))) = self.queue.peek().copied() {
            if t > now {
                break;
            }
            self.queue.pop();
            if let Some(p) = self.pins.get_mut(i) {
                p.external = Some(level);
            }
        }
    }

    fn sense(&self, i: usize) -> u32 {
        self.pins.get(i).map_or(0, |p| (p.cnf >> 16) & 3)
    }

    /// Re-reads the watched inputs (sensing or GPIOTE-watched) after anything that may have
    /// changed them: edges for GPIOTE, LATCH, and whether DETECT rose.
    pub fn settle(&mut self, outside: &mut dyn Outside, now: u64) -> Settled {
        let mut out = Settled::default();
        let mut detect = [false; 2];
        for i in 0..PIN_COUNT {
            let sense = self.sense(i);
            let watched = self.gpiote_watch & (1 << i) != 0;
            if sense == 0 && !watched {
                if let Some(p) = self.pins.get_mut(i) {
                    p.last_level = None;
                }
                continue;
            }
            let level = self.level(i, outside, now);
            let Some(p) = self.pins.get_mut(i) else {
                continue;
            };
            if p.last_level.is_some_and(|l| l != level) && watched {
                out.edges.push((i, level));
            }
            p.last_level = Some(level);
            let met = (sense == 2 && level) || (sense == 3 && !level);
            if met {
                p.latch = true;
            }
            let port = usize::from(i >= 32);
            let ldetect = self.detectmode.get(port).is_some_and(|&m| m & 1 != 0);
            if let Some(d) = detect.get_mut(port) {
                *d |= if ldetect { p.latch } else { met };
            }
        }
        // Latched pins whose sense was turned off still hold DETECT in LDetect mode.
        for (port, d) in detect.iter_mut().enumerate() {
            if self.detectmode.get(port).is_some_and(|&m| m & 1 != 0) {
                *d |= self
                    .port_range(port)
                    .any(|i| self.pins.get(i).is_some_and(|p| p.latch));
            }
        }
        let combined = detect.iter().any(|&d| d);
        out.port_event = combined && !self.detect;
        self.detect = combined;
        out
    }

    fn port_range(&self, port: usize) -> core::ops::Range<usize> {
        if port == 0 { 0..32 } else { 32..PIN_COUNT }
    }

    fn port_bits(&self, port: usize, f: impl Fn(&PinState) -> bool) -> u32 {
        self.port_range(port)
            .enumerate()
            .filter(|&(_, i)| self.pins.get(i).is_some_and(&f))
            .fold(0, |m, (bit, _)| m | (1 << bit))
    }

    /// A GPIO register read (`offset` from 0x5000_0000).
    pub fn read(&mut self, offset: u32, outside: &mut dyn Outside, now: u64) -> Option<u32> {
        let (port, reg) = split(offset)?;
        Some(match reg {
            0x504 => self.port_bits(port, |p| p.out),
            0x510 => {
                let mut bits = 0;
                for (bit, i) in self.port_range(port).enumerate() {
                    let connected = self.pins.get(i).is_some_and(|p| p.cnf & 2 == 0);
                    if connected && self.level(i, outside, now) {
                        bits |= 1 << bit;
                    }
                }
                bits
            }
            0x514 => self.port_bits(port, |p| p.cnf & 1 != 0),
            0x520 => self.port_bits(port, |p| p.latch),
            0x524 => *self.detectmode.get(port)?,
            0x700..0x780 => {
                let i = self.port_range(port).nth(((reg - 0x700) / 4) as usize)?;
                self.pins.get(i)?.cnf
            }
            _ => return None,
        })
    }

    /// A GPIO register write (`offset` from 0x5000_0000); false if not implemented.
    pub fn write(&mut self, offset: u32, value: u32, outside: &mut dyn Outside, now: u64) -> bool {
        let Some((port, reg)) = split(offset) else {
            return false;
        };
        let range = self.port_range(port);
        let each = |pins: &mut Self, f: &dyn Fn(&mut PinState, bool)| {
            for (bit, i) in range.clone().enumerate() {
                if let Some(p) = pins.pins.get_mut(i) {
                    f(p, value & (1 << bit) != 0);
                }
            }
        };
        match reg {
            0x504 => each(self, &|p, b| p.out = b),
            0x508 => each(self, &|p, b| p.out |= b),
            0x50C => each(self, &|p, b| p.out &= !b),
            0x514 => each(self, &|p, b| p.cnf = (p.cnf & !1) | u32::from(b)),
            0x518 => each(self, &|p, b| p.cnf |= u32::from(b)),
            0x51C => each(self, &|p, b| p.cnf &= !u32::from(b)),
            0x520 => {
                each(self, &|p, b| p.latch &= !b);
                if self.detectmode.get(port).is_some_and(|&m| m & 1 != 0) {
                    self.detect = false;
                }
            }
            0x524 => {
                if let Some(m) = self.detectmode.get_mut(port) {
                    *m = value & 1;
                }
            }
            0x700..0x780 => {
                let n = ((reg - 0x700) / 4) as usize;
                let Some(i) = range.clone().nth(n) else {
                    return false;
                };
                if let Some(p) = self.pins.get_mut(i) {
                    p.cnf = value & 0x0003_070F;
                }
            }
            _ => return false,
        }
        for i in range {
            self.refresh(i, outside, now);
        }
        true
    }

    /// Reset: every pin back to a disconnected input (the board hears of each pin that was
    /// driven), LATCH and DETECTMODE cleared. Board-side levels and the queue stay.
    pub fn reset(&mut self, outside: &mut dyn Outside, now: u64) {
        for i in 0..PIN_COUNT {
            if let Some(p) = self.pins.get_mut(i) {
                *p = PinState {
                    external: p.external,
                    reported: p.reported,
                    ..PIN_RESET
                };
            }
            self.refresh(i, outside, now);
        }
        self.detectmode = [0; 2];
        self.detect = false;
        self.gpiote_watch = 0;
    }
}

/// (port, register offset within the port) of a GPIO window offset: P0's registers at
/// 0x500–0x77F, P1's at 0x800–0xA7F.
fn split(offset: u32) -> Option<(usize, u32)> {
    match offset {
        0x500..0x780 => Some((0, offset)),
        0x800..0xA80 => Some((1, offset - 0x300)),
        _ => None,
    }
}
