//! GPIO ports A–I (RM0090 §8): MODER, OTYPER, OSPEEDR, PUPDR, IDR, ODR, BSRR, LCKR and
//! AFRL/H; how each pin is held (GPIO output, a peripheral's alternate function, open drain
//! released, input with pull) reported to the board on every change; inputs from the
//! timestamped queue the board fills, else the board's static level, else the pull.
//!
//! Alternate functions are routed for the signals the modelled peripherals drive (RM0090
//! Table 9 / DS8626 Table 9 "Alternate function mapping"); a pin put on another function
//! is reported as not driven and recorded.

use std::collections::VecDeque;

use crate::wire::{Drive, Outside, Pin, Pull};

/// Ports A–I.
pub const PORTS: usize = 9;

// Register offsets (RM0090 §8.4.11).
const MODER: u32 = 0x00;
const OTYPER: u32 = 0x04;
const OSPEEDR: u32 = 0x08;
const PUPDR: u32 = 0x0C;
const IDR: u32 = 0x10;
const ODR: u32 = 0x14;
const BSRR: u32 = 0x18;
const LCKR: u32 = 0x1C;
const AFRL: u32 = 0x20;
const AFRH: u32 = 0x24;

/// A peripheral signal an alternate function connects to a pin.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Signal {
    /// Timer output compare channel `ch` (1–4) of TIMx.
    Tim {
        /// Timer number (2, 3, 9, …).
        timer: u8,
        /// Channel 1–4.
        ch: u8,
    },
    /// SPIx SCK.
    SpiSck(u8),
    /// SPIx MOSI.
    SpiMosi(u8),
    /// SPIx MISO (an input).
    SpiMiso(u8),
    /// I2Cx SCL (open drain).
    I2cScl(u8),
    /// I2Cx SDA (open drain).
    I2cSda(u8),
    /// USARTx TX.
    UsartTx(u8),
    /// USARTx RX (an input).
    UsartRx(u8),
    /// USB OTG FS D−/D+ (the PHY; not a logic level).
    OtgFs,
    /// SWJ debug port (JTAG/SWD): not driven without a debugger.
    Debug,
}

/// The signal alternate function `af` connects to pin `pin` of port `port`, for the
/// peripherals this crate models.
pub fn af_signal(port: u8, pin: u8, af: u8) -> Option<Signal> {
    use Signal::*;
    Some(match (port, pin, af) {
        (0, 13..=15, 0) | (1, 3 | 4, 0) => Debug,
        (0, 0, 1) => Tim { timer: 2, ch: 1 },
        (0, 1, 1) => Tim { timer: 2, ch: 2 },
        (0, 2, 1) => Tim { timer: 2, ch: 3 },
        (0, 3, 1) => Tim { timer: 2, ch: 4 },
        (0, 5, 1) | (0, 15, 1) => Tim { timer: 2, ch: 1 },
        (0, 6, 2) | (1, 4, 2) | (2, 6, 2) => Tim { timer: 3, ch: 1 },
        (0, 7, 2) | (1, 5, 2) | (2, 7, 2) => Tim { timer: 3, ch: 2 },
        (1, 0, 2) | (2, 8, 2) => Tim { timer: 3, ch: 3 },
        (1, 1, 2) | (2, 9, 2) => Tim { timer: 3, ch: 4 },
        (0, 2, 3) | (4, 5, 3) => Tim { timer: 9, ch: 1 },
        (0, 3, 3) | (4, 6, 3) => Tim { timer: 9, ch: 2 },
        (1, 6 | 8, 4) => I2cScl(1),
        (1, 7 | 9, 4) => I2cSda(1),
        (0, 5, 5) | (1, 3, 5) => SpiSck(1),
        (0, 6, 5) | (1, 4, 5) => SpiMiso(1),
        (0, 7, 5) | (1, 5, 5) => SpiMosi(1),
        (2, 10, 6) | (1, 3, 6) => SpiSck(3),
        (2, 11, 6) | (1, 4, 6) => SpiMiso(3),
        (2, 12, 6) | (1, 5, 6) => SpiMosi(3),
        (0, 9, 7) | (1, 6, 7) => UsartTx(1),
        (0, 10, 7) | (1, 7, 7) => UsartRx(1),
        (0, 11 | 12, 10) => OtgFs,
        _ => return None,
    })
}

/// How a peripheral drives one of its output signals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SignalDrive {
    /// Not driven (peripheral off, output disabled, an input or an open-drain release).
    Off,
    /// Driven to this level.
    Level(bool),
}

/// One port's registers.
#[derive(Clone, Copy, Debug)]
struct Port {
    moder: u32,
    otyper: u32,
    ospeedr: u32,
    pupdr: u32,
    odr: u32,
    afr: [u32; 2],
    /// LCKR: the lock key sequence stage and the locked pins.
    lck_stage: u8,
    lck_pins: u32,
    locked: bool,
}

impl Port {
    /// Reset values (RM0090 §8.4): PA13–15 and PB3–4 start in the debug port's AF0 with
    /// pulls.
    fn reset(index: usize) -> Self {
        let (moder, ospeedr, pupdr) = match index {
            0 => (0xA800_0000, 0x0C00_0000, 0x6400_0000),
            1 => (0x0000_0280, 0x0000_00C0, 0x0000_0100),
            _ => (0, 0, 0),
        };
        Self {
            moder,
            otyper: 0,
            ospeedr,
            pupdr,
            odr: 0,
            afr: [0; 2],
            lck_stage: 0,
            lck_pins: 0,
            locked: false,
        }
    }

    fn mode(&self, n: u8) -> u32 {
        (self.moder >> (2 * n)) & 3
    }

    fn af(&self, n: u8) -> u8 {
        let reg = if n < 8 { self.afr[0] } else { self.afr[1] };
        ((reg >> (4 * (n % 8))) & 0xF) as u8
    }

    fn pull(&self, n: u8) -> Pull {
        match (self.pupdr >> (2 * n)) & 3 {
            1 => Pull::Up,
            2 => Pull::Down,
            _ => Pull::None,
        }
    }

    fn open_drain(&self, n: u8) -> bool {
        self.otyper & (1 << n) != 0
    }

    fn out(&self, n: u8) -> bool {
        self.odr & (1 << n) != 0
    }
}

/// A timestamped input level the board queued.
#[derive(Clone, Copy, Debug)]
struct InputEvent {
    at_ns: u64,
    pin: Pin,
    level: bool,
}

/// An input pin's level changed at `at_ns` (for EXTI).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelChange {
    /// The pin.
    pub pin: Pin,
    /// Its new level.
    pub level: bool,
    /// When.
    pub at_ns: u64,
}

/// All ports.
pub struct Gpio {
    ports: [Port; PORTS],
    /// What the board was last told for each pin.
    reported: [[Option<Drive>; 16]; PORTS],
    /// The last level the board queued for each pin.
    external: [[Option<bool>; 16]; PORTS],
    /// Output signals of the peripherals.
    signals: Vec<(Signal, SignalDrive)>,
    /// Pins in AF mode, with their signal (rebuilt on configuration changes).
    af_pins: Vec<(Signal, Pin)>,
    /// Pins on an alternate function no model drives.
    pub unrouted: Vec<(Pin, u8)>,
    queue: VecDeque<InputEvent>,
}

impl Default for Gpio {
    fn default() -> Self {
        Self::new()
    }
}

impl Gpio {
    /// Reset state.
    pub fn new() -> Self {
        let mut g = Self {
            ports: std::array::from_fn(Port::reset),
            reported: [[None; 16]; PORTS],
            external: [[None; 16]; PORTS],
            signals: Vec::new(),
            af_pins: Vec::new(),
            unrouted: Vec::new(),
            queue: VecDeque::new(),
        };
        g.rebuild_af();
        g
    }

    /// A system reset: registers to reset values (the board is told at the next refresh);
    /// queued inputs and the board's levels stay.
    pub fn reset(&mut self) {
        self.ports = std::array::from_fn(Port::reset);
        self.signals.clear();
        self.rebuild_af();
    }

    /// Port `index` alone back to its reset values (RCC_AHB1RSTR).
    pub fn reset_port(&mut self, index: usize) {
        if let Some(p) = self.ports.get_mut(index) {
            *p = Port::reset(index);
        }
        self.rebuild_af();
    }

    fn port(&self, p: u8) -> Option<&Port> {
        self.ports.get(usize::from(p))
    }

    /// Queues an input level the board puts on `pin` from `at_ns` on.
    pub fn drive_input(&mut self, pin: Pin, level: bool, at_ns: u64) {
        let ev = InputEvent { at_ns, pin, level };
        // Usually appended in order; keep the queue sorted by time otherwise.
        let pos = self
            .queue
            .iter()
            .rposition(|e| e.at_ns <= at_ns)
            .map_or(0, |i| i + 1);
        self.queue.insert(pos, ev);
    }

    /// The time of the next queued input.
    pub fn next_event(&self) -> u64 {
        self.queue.front().map_or(u64::MAX, |e| e.at_ns)
    }

    /// Applies queued inputs due by `now`; returns the effective level changes.
    pub fn process<O: Outside>(&mut self, now: u64, outside: &mut O) -> Vec<LevelChange> {
        let mut changes = Vec::new();
        while let Some(ev) = self.queue.front().copied() {
            if ev.at_ns > now {
                break;
            }
            self.queue.pop_front();
            let before = self.level(ev.pin, outside, ev.at_ns);
            if let Some(slot) = self
                .external
                .get_mut(usize::from(ev.pin.port))
                .and_then(|p| p.get_mut(usize::from(ev.pin.pin)))
            {
                *slot = Some(ev.level);
            }
            let after = self.level(ev.pin, outside, ev.at_ns);
            if before != after {
                changes.push(LevelChange {
                    pin: ev.pin,
                    level: after,
                    at_ns: ev.at_ns,
                });
            }
        }
        changes
    }

    /// The level the pin's input stage sees (IDR): the chip's own push-pull or low
    /// open-drain drive, else the board (queued level, else its static level), else the
    /// pull; a floating pin reads 0. Analog pins read 0 (RM0090 §8.3.12).
    pub fn level<O: Outside>(&self, pin: Pin, outside: &mut O, now: u64) -> bool {
        let Some(port) = self.port(pin.port) else {
            return false;
        };
        if pin.pin > 15 || port.mode(pin.pin) == 3 {
            return false;
        }
        match self.drive(pin) {
            Drive::Low => false,
            Drive::High => true,
            Drive::Released(pull) => {
                let external = self
                    .external
                    .get(usize::from(pin.port))
                    .and_then(|p| p.get(usize::from(pin.pin)))
                    .copied()
                    .flatten();
                external
                    .or_else(|| outside.pin_level(pin, now))
                    .unwrap_or(pull == Pull::Up)
            }
        }
    }

    /// Like [`Gpio::level`], but `None` for a floating pin (no drive, no board level, no
    /// pull): a level nobody sets is not a fact to act on.
    pub fn level_opt<O: Outside>(&self, pin: Pin, outside: &mut O, now: u64) -> Option<bool> {
        let port = self.port(pin.port)?;
        if pin.pin > 15 || port.mode(pin.pin) == 3 {
            return None;
        }
        match self.drive(pin) {
            Drive::Low => Some(false),
            Drive::High => Some(true),
            Drive::Released(pull) => self
                .external
                .get(usize::from(pin.port))
                .and_then(|p| p.get(usize::from(pin.pin)))
                .copied()
                .flatten()
                .or_else(|| outside.pin_level(pin, now))
                .or(match pull {
                    Pull::Up => Some(true),
                    Pull::Down => Some(false),
                    Pull::None => None,
                }),
        }
    }

    /// How the chip holds `pin` now.
    pub fn drive(&self, pin: Pin) -> Drive {
        let Some(port) = self.port(pin.port) else {
            return Drive::Released(Pull::None);
        };
        let n = pin.pin;
        let pull = port.pull(n);
        let level_drive = |level: bool| {
            if !level {
                Drive::Low
            } else if port.open_drain(n) {
                Drive::Released(pull)
            } else {
                Drive::High
            }
        };
        match port.mode(n) {
            0 => Drive::Released(pull),
            1 => level_drive(port.out(n)),
            2 => match af_signal(pin.port, n, port.af(n)).map(|s| self.signal(s)) {
                Some(SignalDrive::Level(l)) => level_drive(l),
                _ => Drive::Released(pull),
            },
            _ => Drive::Released(Pull::None),
        }
    }

    fn signal(&self, s: Signal) -> SignalDrive {
        self.signals
            .iter()
            .find(|(sig, _)| *sig == s)
            .map_or(SignalDrive::Off, |&(_, d)| d)
    }

    /// A peripheral output changed at `now`: pins on that function follow.
    pub fn set_signal<O: Outside>(&mut self, s: Signal, d: SignalDrive, outside: &mut O, now: u64) {
        match self.signals.iter_mut().find(|(sig, _)| *sig == s) {
            Some(slot) if slot.1 == d => return,
            Some(slot) => slot.1 = d,
            None => self.signals.push((s, d)),
        }
        let pins: Vec<Pin> = self
            .af_pins
            .iter()
            .filter(|(sig, _)| *sig == s)
            .map(|&(_, p)| p)
            .collect();
        for pin in pins {
            self.report(pin, outside, now);
        }
    }

    /// Tells the board about `pin` if its drive changed.
    fn report<O: Outside>(&mut self, pin: Pin, outside: &mut O, now: u64) -> bool {
        let drive = self.drive(pin);
        let Some(slot) = self
            .reported
            .get_mut(usize::from(pin.port))
            .and_then(|p| p.get_mut(usize::from(pin.pin)))
        else {
            return false;
        };
        if *slot == Some(drive) {
            return false;
        }
        *slot = Some(drive);
        outside.pin_driven(pin, drive, now);
        true
    }

    /// An unpowered chip drives nothing: every pin released, no pulls, told to the board.
    pub fn release_all<O: Outside>(&mut self, outside: &mut O, now: u64) {
        for (port, pins) in self.reported.iter_mut().enumerate() {
            for (n, slot) in pins.iter_mut().enumerate() {
                let off = Drive::Released(Pull::None);
                if *slot != Some(off) {
                    *slot = Some(off);
                    outside.pin_driven(Pin::new(port as u8, n as u8), off, now);
                }
            }
        }
    }

    /// Reports every pin whose drive changed (after a register write or reset); returns
    /// the pins that changed.
    pub fn refresh<O: Outside>(&mut self, outside: &mut O, now: u64) -> Vec<Pin> {
        let mut changed = Vec::new();
        for port in 0..PORTS as u8 {
            for n in 0..16 {
                let pin = Pin::new(port, n);
                if self.report(pin, outside, now) {
                    changed.push(pin);
                }
            }
        }
        changed
    }

    fn rebuild_af(&mut self) {
        self.af_pins.clear();
        for (pi, port) in self.ports.iter().enumerate() {
            for n in 0..16u8 {
                if port.mode(n) != 2 {
                    continue;
                }
                let pin = Pin::new(pi as u8, n);
                match af_signal(pin.port, n, port.af(n)) {
                    Some(s) => self.af_pins.push((s, pin)),
                    None => {
                        if !self.unrouted.contains(&(pin, port.af(n))) {
                            self.unrouted.push((pin, port.af(n)));
                        }
                    }
                }
            }
        }
    }

    /// Register read.
    pub fn read<O: Outside>(
        &mut self,
        port: u8,
        offset: u32,
        outside: &mut O,
        now: u64,
    ) -> Option<u32> {
        let p = *self.port(port)?;
        Some(match offset {
            MODER => p.moder,
            OTYPER => p.otyper,
            OSPEEDR => p.ospeedr,
            PUPDR => p.pupdr,
            IDR => (0..16u8).fold(0, |acc, n| {
                acc | u32::from(self.level(Pin::new(port, n), outside, now)) << n
            }),
            ODR => p.odr,
            BSRR => 0,
            LCKR => {
                let v = p.lck_pins | if p.locked { 1 << 16 } else { 0 };
                if p.lck_stage == 3 {
                    if let Some(pm) = self.ports.get_mut(usize::from(port)) {
                        pm.locked = true;
                        pm.lck_stage = 0;
                    }
                    return Some(p.lck_pins | 1 << 16);
                }
                v
            }
            AFRL => p.afr[0],
            AFRH => p.afr[1],
            _ => return None,
        })
    }

    /// Register write (`mask`: the byte lanes written); the board hears of every pin whose
    /// drive changed.
    pub fn write<O: Outside>(
        &mut self,
        port: u8,
        offset: u32,
        value: u32,
        mask: u32,
        outside: &mut O,
        now: u64,
    ) -> Option<Vec<Pin>> {
        let p = self.ports.get_mut(usize::from(port))?;
        let locked = if p.locked { p.lck_pins & 0xFFFF } else { 0 };
        // Bits of a locked pin (1 bit per pin, 2 bits per pin, 4 bits per pin).
        let lock1 = locked;
        let lock2 = (0..16).fold(0u32, |a, n| {
            a | if locked & (1 << n) != 0 {
                3 << (2 * n)
            } else {
                0
            }
        });
        let lock4 = |half: u32| {
            (0..8).fold(0u32, |a, n| {
                a | if locked & (1 << (n + 8 * half)) != 0 {
                    0xF << (4 * n)
                } else {
                    0
                }
            })
        };
        let merge = |old: u32, keep: u32| (old & (!mask | keep)) | (value & mask & !keep);
        let mut config_changed = false;
        match offset {
            MODER => {
                p.moder = merge(p.moder, lock2);
                config_changed = true;
            }
            OTYPER => p.otyper = merge(p.otyper, lock1) & 0xFFFF,
            OSPEEDR => p.ospeedr = merge(p.ospeedr, lock2),
            PUPDR => p.pupdr = merge(p.pupdr, lock2),
            IDR => {}
            ODR => p.odr = merge(p.odr, 0) & 0xFFFF,
            BSRR => {
                let v = value & mask;
                // Set wins over reset when both bits are written (RM0090 §8.4.7).
                p.odr = (p.odr & !(v >> 16) | (v & 0xFFFF)) & 0xFFFF;
            }
            LCKR => {
                let key = value & (1 << 16) != 0;
                let pins = value & 0xFFFF;
                p.lck_stage = match (p.lck_stage, key) {
                    (0, true) => {
                        p.lck_pins = pins;
                        1
                    }
                    (1, false) if pins == p.lck_pins => 2,
                    (2, true) if pins == p.lck_pins => 3,
                    _ => 0,
                };
            }
            AFRL => {
                p.afr[0] = merge(p.afr[0], lock4(0));
                config_changed = true;
            }
            AFRH => {
                p.afr[1] = merge(p.afr[1], lock4(1));
                config_changed = true;
            }
            _ => return None,
        }
        if config_changed {
            self.rebuild_af();
        }
        let mut changed = Vec::new();
        for n in 0..16 {
            let pin = Pin::new(port, n);
            if self.report(pin, outside, now) {
                changed.push(pin);
            }
        }
        Some(changed)
    }

    /// The pins on an alternate function `s`.
    pub fn pins_of(&self, s: Signal) -> Vec<Pin> {
        self.af_pins
            .iter()
            .filter(|(sig, _)| *sig == s)
            .map(|&(_, p)| p)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stm32f405::testing::Board;

    #[test]
    fn reset_state_releases_every_pin_with_the_debug_pulls() {
        let mut g = Gpio::new();
        let mut b = Board::default();
        g.refresh(&mut b, 0);
        assert_eq!(
            b.drive(Pin::new(0, 15)),
            Some(Drive::Released(Pull::Up)),
            "PA15 JTDI"
        );
        assert_eq!(
            b.drive(Pin::new(0, 14)),
            Some(Drive::Released(Pull::Down)),
            "PA14 SWCLK"
        );
        assert_eq!(
            b.drive(Pin::new(1, 4)),
            Some(Drive::Released(Pull::Up)),
            "PB4 NJTRST"
        );
        assert_eq!(b.drive(Pin::new(1, 0)), Some(Drive::Released(Pull::None)));
        assert_eq!(b.pins.len(), PORTS * 16);
    }

    #[test]
    fn embassy_output_new_drives_the_pin_and_bsrr_toggles_it() {
        // Output::new(PB5, Level::High, Speed::Low): BSRR set, PUPDR, OTYPER, OSPEEDR, MODER.
        let mut g = Gpio::new();
        let mut b = Board::default();
        g.refresh(&mut b, 0);
        b.pins.clear();
        g.write(1, BSRR, 1 << 5, !0, &mut b, 10);
        assert!(b.pins.is_empty(), "ODR alone does not drive an input pin");
        g.write(1, MODER, 0x0000_0280 | 1 << 10, !0, &mut b, 20);
        assert_eq!(b.pins, vec![(Pin::new(1, 5), Drive::High, 20)]);
        g.write(1, BSRR, 1 << 21, !0, &mut b, 30);
        assert_eq!(b.pins.last(), Some(&(Pin::new(1, 5), Drive::Low, 30)));
        assert_eq!(g.read(1, ODR, &mut b, 30), Some(0));
        assert_eq!(g.read(1, IDR, &mut b, 30).unwrap() & 1 << 5, 0);
        // Both set and reset written: set wins.
        g.write(1, BSRR, 1 << 5 | 1 << 21, !0, &mut b, 40);
        assert_eq!(g.read(1, ODR, &mut b, 40), Some(1 << 5));
    }

    #[test]
    fn open_drain_releases_high_and_reads_the_bus() {
        let mut g = Gpio::new();
        let mut b = Board::default();
        // PB9 open drain with pull-up, high: released; the board holds the line low.
        g.write(1, OTYPER, 1 << 9, !0, &mut b, 0);
        g.write(1, PUPDR, 0x100 | 1 << 18, !0, &mut b, 0);
        g.write(1, ODR, 1 << 9, !0, &mut b, 0);
        g.write(1, MODER, 0x280 | 1 << 18, !0, &mut b, 0);
        assert_eq!(b.drive(Pin::new(1, 9)), Some(Drive::Released(Pull::Up)));
        b.levels.insert(Pin::new(1, 9), false);
        assert_eq!(g.read(1, IDR, &mut b, 0).unwrap() & 1 << 9, 0);
        b.levels.remove(&Pin::new(1, 9));
        assert_eq!(
            g.read(1, IDR, &mut b, 0).unwrap() & 1 << 9,
            1 << 9,
            "pull-up"
        );
        g.write(1, ODR, 0, !0, &mut b, 5);
        assert_eq!(b.drive(Pin::new(1, 9)), Some(Drive::Low));
    }

    #[test]
    fn alternate_functions_follow_their_peripheral() {
        let mut g = Gpio::new();
        let mut b = Board::default();
        // PB0 on AF2 = TIM3_CH3.
        g.write(1, AFRL, 2, !0, &mut b, 0);
        g.write(1, MODER, 0x280 | 2, !0, &mut b, 0);
        assert_eq!(b.drive(Pin::new(1, 0)), Some(Drive::Released(Pull::None)));
        g.set_signal(
            Signal::Tim { timer: 3, ch: 3 },
            SignalDrive::Level(true),
            &mut b,
            100,
        );
        assert_eq!(b.pins.last(), Some(&(Pin::new(1, 0), Drive::High, 100)));
        g.set_signal(
            Signal::Tim { timer: 3, ch: 3 },
            SignalDrive::Level(false),
            &mut b,
            150,
        );
        assert_eq!(b.pins.last(), Some(&(Pin::new(1, 0), Drive::Low, 150)));
        // An AF no model drives is recorded.
        g.write(2, MODER, 2 << 30, !0, &mut b, 0);
        assert_eq!(g.unrouted, vec![(Pin::new(2, 15), 0)]);
    }

    #[test]
    fn queued_inputs_apply_at_their_time() {
        let mut g = Gpio::new();
        let mut b = Board::default();
        g.drive_input(Pin::new(2, 5), true, 1_000);
        g.drive_input(Pin::new(2, 5), false, 3_000);
        g.drive_input(Pin::new(2, 5), true, 2_000);
        assert_eq!(g.next_event(), 1_000);
        assert_eq!(g.process(1_500, &mut b).len(), 1);
        assert_eq!(g.read(2, IDR, &mut b, 1_500).unwrap() & 1 << 5, 1 << 5);
        let ch = g.process(5_000, &mut b);
        assert_eq!(ch.len(), 1, "2 µs repeats the high level: no change");
        assert_eq!(ch[0].at_ns, 3_000);
        assert!(!ch[0].level);
    }

    #[test]
    fn a_locked_pin_keeps_its_configuration() {
        let mut g = Gpio::new();
        let mut b = Board::default();
        g.write(2, MODER, 1 << 8, !0, &mut b, 0);
        for v in [1 << 16 | 1 << 4, 1 << 4, 1 << 16 | 1 << 4] {
            g.write(2, LCKR, v, !0, &mut b, 0);
        }
        g.read(2, LCKR, &mut b, 0);
        assert_eq!(g.read(2, LCKR, &mut b, 0), Some(1 << 16 | 1 << 4));
        g.write(2, MODER, 0, !0, &mut b, 0);
        assert_eq!(g.read(2, MODER, &mut b, 0), Some(1 << 8));
    }
}
