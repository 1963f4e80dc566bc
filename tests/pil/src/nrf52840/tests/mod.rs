//! Unit tests: each block driven with the register sequences embassy-nrf 0.11 uses, checked
//! against what the nRF52840 Product Specification says happens.

// Register addresses read as base + offset, also for offset 0.
#![allow(clippy::identity_op)]

mod boot;
mod clock;
mod decode;
mod gpio;
mod memory;
mod pwm;
mod rng;
mod rtc;
mod saadc;
mod spim;
mod timer_ppi;
mod uarte;
mod wdt;

use std::collections::{HashMap, VecDeque};

use m4_sim::{Bus, Width};

use super::{Config, Nrf52840};
use crate::wire::{Drive, I2cReply, I2cStep, Outside, Pin};

/// A board that records what the chip does and answers from tables.
#[derive(Default)]
pub struct Board {
    pub driven: Vec<(Pin, Drive, u64)>,
    pub levels: HashMap<Pin, bool>,
    pub spi: Vec<(u8, u8, u64)>,
    pub miso: VecDeque<u8>,
    pub uart: Vec<(u8, u8, u64)>,
    pub volts: HashMap<Pin, f32>,
}

impl Outside for Board {
    fn pin_driven(&mut self, pin: Pin, drive: Drive, now_ns: u64) {
        self.driven.push((pin, drive, now_ns));
    }
    fn pin_level(&mut self, pin: Pin, _now_ns: u64) -> Option<bool> {
        self.levels.get(&pin).copied()
    }
    fn spi_byte(&mut self, bus: u8, mosi: u8, now_ns: u64) -> u8 {
        self.spi.push((bus, mosi, now_ns));
        self.miso.pop_front().unwrap_or(0xFF)
    }
    fn i2c_step(&mut self, _bus: u8, _step: I2cStep, _now_ns: u64) -> I2cReply {
        I2cReply::Nack
    }
    fn uart_sent(&mut self, uart: u8, byte: u8, now_ns: u64) {
        self.uart.push((uart, byte, now_ns));
    }
    fn analog_volts(&mut self, pin: Pin, _now_ns: u64) -> f32 {
        self.volts.get(&pin).copied().unwrap_or(0.0)
    }
}

pub type Chip = Nrf52840<Board>;

pub fn chip() -> Chip {
    Nrf52840::new(Board::default(), Config::default())
}

pub fn chip_with(config: Config) -> Chip {
    Nrf52840::new(Board::default(), config)
}

pub fn w(c: &mut Chip, addr: u32, value: u32, t: u64) {
    c.write(addr, Width::Word, value, t).unwrap();
}

pub fn r(c: &mut Chip, addr: u32, t: u64) -> u32 {
    c.read(addr, Width::Word, t).unwrap()
}

pub fn irq(c: &Chip, n: u32) -> bool {
    c.irq_lines()[(n / 32) as usize] & (1 << (n % 32)) != 0
}

/// Starts the LFCLK from the crystal as embassy-nrf's `init` does and waits for it; returns
/// the time it runs from.
pub fn start_lfxo(c: &mut Chip, t: u64) -> u64 {
    w(c, 0x4000_0518, 1, t);
    w(c, 0x4000_0104, 0, t);
    w(c, 0x4000_0008, 1, t);
    let started = c.next_event_ns();
    c.advance(started);
    assert_eq!(r(c, 0x4000_0104, started), 1);
    started
}

/// Runs the board's inputs and the chip's events up to `t`.
pub fn run_to(c: &mut Chip, t: u64) {
    c.advance(t);
}
