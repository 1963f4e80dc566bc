//! A recording board for the unit tests: every call the SoC makes is kept with its time,
//! and the tests script what the board answers.

use std::collections::{HashMap, VecDeque};

use crate::wire::{Drive, I2cReply, I2cStep, Outside, Pin};

/// Records everything; answers from its scripts.
#[derive(Default)]
pub struct Board {
    /// Every pin change.
    pub pins: Vec<(Pin, Drive, u64)>,
    /// Static levels the board puts on pins.
    pub levels: HashMap<Pin, bool>,
    /// Every SPI byte: bus, MOSI, time.
    pub spi: Vec<(u8, u8, u64)>,
    /// MISO bytes to answer, in order (0xFF when empty).
    pub miso: VecDeque<u8>,
    /// Every I²C step with its time.
    pub i2c: Vec<(u8, I2cStep, u64)>,
    /// Replies to I²C steps, in order (`Ack`, or `Data(0xFF)` for reads, when empty).
    pub i2c_replies: VecDeque<I2cReply>,
    /// Bytes the UARTs sent.
    pub uart: Vec<(u8, u8, u64)>,
    /// Analog inputs, volts.
    pub volts: HashMap<Pin, f32>,
}

impl Board {
    /// The last drive reported for `pin`.
    pub fn drive(&self, pin: Pin) -> Option<Drive> {
        self.pins
            .iter()
            .rev()
            .find(|(p, _, _)| *p == pin)
            .map(|&(_, d, _)| d)
    }

    /// The changes reported for `pin`, with their times.
    pub fn edges(&self, pin: Pin) -> Vec<(Drive, u64)> {
        self.pins
            .iter()
            .filter(|(p, _, _)| *p == pin)
            .map(|&(_, d, t)| (d, t))
            .collect()
    }
}

impl Outside for Board {
    fn pin_driven(&mut self, pin: Pin, drive: Drive, now_ns: u64) {
        self.pins.push((pin, drive, now_ns));
    }

    fn pin_level(&mut self, pin: Pin, _now_ns: u64) -> Option<bool> {
        self.levels.get(&pin).copied()
    }

    fn spi_byte(&mut self, bus: u8, mosi: u8, now_ns: u64) -> u8 {
        self.spi.push((bus, mosi, now_ns));
        self.miso.pop_front().unwrap_or(0xFF)
    }

    fn i2c_step(&mut self, bus: u8, step: I2cStep, now_ns: u64) -> I2cReply {
        self.i2c.push((bus, step, now_ns));
        self.i2c_replies.pop_front().unwrap_or(match step {
            I2cStep::Read { .. } => I2cReply::Data(0xFF),
            _ => I2cReply::Ack,
        })
    }

    fn uart_sent(&mut self, uart: u8, byte: u8, now_ns: u64) {
        self.uart.push((uart, byte, now_ns));
    }

    fn analog_volts(&mut self, pin: Pin, _now_ns: u64) -> f32 {
        self.volts.get(&pin).copied().unwrap_or(0.0)
    }
}
