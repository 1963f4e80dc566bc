//! The MEAS MS5611-01BA03 barometer on I²C (datasheet DA5611-01BA03, "I²C interface",
//! "Commands", "Pressure and temperature calculation"; AN520 for the PROM's CRC-4): address
//! 0x77 with CSB low, RESET (0x1E, 2.8 ms), CONVERT D1/D2 at OSR 256…4096 with the
//! datasheet's maximum conversion times, ADC READ (0x00: 24 bits, MSB first; 0 when no
//! conversion finished since the last read, or one is still running), PROM READ
//! (0xA0…0xAE: eight 16-bit words, word 7's low nibble the CRC-4). D1 and D2 are the inverse
//! of the datasheet's first-order compensation of the true pressure (ISA atmosphere at the
//! true altitude, plus the world's altitude noise) and temperature, so the driver's own
//! compensation reads them back.
//!
//! **Stuck bus**: [`Ms5611::hold_sda_low`] leaves the chip as an MCU reset in the middle of a
//! read does — driving a 0 bit on SDA, waiting for SCL to clock its byte out. Every I²C step
//! then sees the bus held ([`I2cReply::Stuck`]); only SCL pulses (seen as the pin's rising
//! edges while the firmware bit-bangs it as GPIO, [`Ms5611::scl`]) release SDA, after the
//! byte's remaining bits and the acknowledge slot (at most 9), and the chip answers its
//! address again only after a STOP (SDA rising while SCL is high, [`Ms5611::sda`]).

use crate::wire::{I2cReply, I2cStep};

/// The 7-bit address with CSB tied low (datasheet: 111011Cx, C = the complement of CSB).
pub const ADDRESS: u8 = 0x77;
/// RESET reloads the PROM; the datasheet gives 2.8 ms.
pub const RESET_NS: u64 = 2_800_000;
/// Maximum conversion times for OSR 256, 512, 1024, 2048, 4096, ns (datasheet, "Operating
/// conditions": 0.60, 1.17, 2.28, 4.54, 9.04 ms).
pub const CONVERSION_NS: [u64; 5] = [600_000, 1_170_000, 2_280_000, 4_540_000, 9_040_000];
/// The calibration of this chip: the datasheet's typical values C1…C6 (its worked example).
pub const CALIBRATION: [u16; 6] = [40_127, 36_924, 23_317, 23_282, 33_464, 28_312];
/// PROM word 0 (factory data) and the serial code in word 7's upper bits.
const FACTORY_WORD: u16 = 0x0051;
const SERIAL_BITS: u16 = 0x4A50;

/// PROM words 0–7 with the CRC-4 of AN520 in word 7's low nibble.
pub fn prom() -> [u16; 8] {
    let mut words = [0u16; 8];
    words[0] = FACTORY_WORD;
    words[1..7].copy_from_slice(&CALIBRATION);
    words[7] = SERIAL_BITS & 0xFFF0;
    words[7] |= u16::from(crc4(&words));
    words
}

/// AN520's CRC-4 over the eight PROM words with word 7's low byte taken as zero.
pub fn crc4(words: &[u16; 8]) -> u8 {
    let mut rem: u16 = 0;
    for i in 0..16 {
        let word = words.get(i / 2).copied().unwrap_or(0);
        let word = if i / 2 == 7 { word & 0xFF00 } else { word };
        rem ^= if i % 2 == 1 { word & 0x00FF } else { word >> 8 };
        for _ in 0..8 {
            rem = if rem & 0x8000 != 0 {
                (rem << 1) ^ 0x3000
            } else {
                rem << 1
            };
        }
    }
    ((rem >> 12) & 0x0F) as u8
}

/// Pressure of the International Standard Atmosphere at `altitude_m` above sea level, Pa.
pub fn isa_pressure_pa(altitude_m: f64) -> f64 {
    101_325.0 * (1.0 - 2.255_77e-5 * altitude_m).powf(5.255_88)
}

/// D1 and D2 for `pressure_pa` and `temp_c`: the first-order compensation of the datasheet
/// inverted (valid at or above 20 °C, where the second order adds nothing).
pub fn raw_for(pressure_pa: f64, temp_c: f64) -> (u32, u32) {
    let c = CALIBRATION.map(f64::from);
    let [c1, c2, c3, c4, c5, c6] = c;
    let temp = temp_c * 100.0;
    let dt = (temp - 2000.0) * 8_388_608.0 / c6;
    let d2 = c5 * 256.0 + dt;
    let off = c2 * 65_536.0 + c4 * dt / 128.0;
    let sens = c1 * 32_768.0 + c3 * dt / 256.0;
    // P in 0.01 mbar = Pa.
    let d1 = (pressure_pa * 32_768.0 + off) * 2_097_152.0 / sens;
    let clamp = |v: f64| v.round().clamp(0.0, 16_777_215.0) as u32;
    (clamp(d1), clamp(d2))
}

/// What the chip is doing on the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Bus {
    /// Waiting for its address.
    Idle,
    /// Addressed for a write: the next byte is a command.
    Command,
    /// Addressed for a read: sending these bytes.
    Reading { bytes: [u8; 3], len: u8, next: u8 },
    /// Not addressed (another address, or a NACKed byte): ignoring until START/STOP.
    Ignoring,
    /// Holding SDA low, waiting for `pulses` more SCL pulses.
    Holding { pulses: u8 },
    /// SDA released after a stuck read; ignoring everything until a STOP.
    AwaitingStop,
}

/// What a read transaction returns: the ADC result, or a PROM word.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PendingRead {
    Adc,
    Prom(u8),
}

/// A conversion running or done.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Conversion {
    d1: bool,
    done_ns: u64,
}

/// The chip.
#[derive(Debug, Clone)]
pub struct Ms5611 {
    bus: Bus,
    pending_read: PendingRead,
    /// RESET reloads the PROM until then; the chip does not acknowledge meanwhile.
    busy_until_ns: u64,
    conversion: Option<Conversion>,
    /// The result of the last finished conversion, until read.
    adc: Option<u32>,
    /// The truth the next finishing conversion measures.
    pressure_pa: f64,
    temp_c: f64,
    /// SCL and SDA as the bus is (high = released).
    scl_high: bool,
    sda_high: bool,
    /// Conversions finished so far.
    conversions: u64,
}

impl Default for Ms5611 {
    fn default() -> Self {
        Self::new()
    }
}

impl Ms5611 {
    /// A chip after power-on, at sea level and 25 °C until told the truth.
    pub fn new() -> Self {
        Self {
            bus: Bus::Idle,
            pending_read: PendingRead::Adc,
            busy_until_ns: 0,
            conversion: None,
            adc: None,
            pressure_pa: isa_pressure_pa(0.0),
            temp_c: 25.0,
            scl_high: true,
            sda_high: true,
            conversions: 0,
        }
    }

    /// Conversions finished since power-on.
    pub fn conversions(&self) -> u64 {
        self.conversions
    }

    /// The truth at `now_ns`: pressure (Pa) and die temperature (°C). A conversion that
    /// finished by now latches it (the world calls this at least every physics step).
    pub fn set_truth(&mut self, now_ns: u64, pressure_pa: f64, temp_c: f64) {
        self.finish_conversion(now_ns);
        self.pressure_pa = pressure_pa;
        self.temp_c = temp_c;
    }

    fn finish_conversion(&mut self, now_ns: u64) {
        if let Some(c) = self.conversion.filter(|c| c.done_ns <= now_ns) {
            let (d1, d2) = raw_for(self.pressure_pa, self.temp_c);
            self.adc = Some(if c.d1 { d1 } else { d2 });
            self.conversion = None;
            self.conversions += 1;
        }
    }

    /// The chip holds SDA low as if an MCU reset had cut a read short: `pulses` (1–9) SCL
    /// pulses clock out the rest of its byte and the acknowledge slot.
    pub fn hold_sda_low(&mut self, pulses: u8) {
        self.bus = Bus::Holding {
            pulses: pulses.clamp(1, 9),
        };
    }

    /// Whether the chip pulls SDA low now.
    pub fn holds_sda(&self) -> bool {
        matches!(self.bus, Bus::Holding { .. })
    }

    /// Whether the chip is out of its stuck state only waiting for a STOP.
    pub fn awaits_stop(&self) -> bool {
        self.bus == Bus::AwaitingStop
    }

    /// SCL as the bus carries it (high = released by everyone). A rising edge while the
    /// chip holds SDA clocks one bit out.
    pub fn scl(&mut self, high: bool) {
        if high
            && !self.scl_high
            && let Bus::Holding { pulses } = self.bus
        {
            self.bus = if pulses <= 1 {
                Bus::AwaitingStop
            } else {
                Bus::Holding { pulses: pulses - 1 }
            };
        }
        self.scl_high = high;
    }

    /// SDA as the MCU leaves it (high = released). Rising while SCL is high is a STOP.
    pub fn sda(&mut self, high: bool) {
        if high && !self.sda_high && self.scl_high && !self.holds_sda() {
            self.bus = Bus::Idle;
        }
        self.sda_high = high;
    }

    /// One step of a transaction the MCU's I²C controller makes at `now_ns`.
    pub fn step(&mut self, step: I2cStep, now_ns: u64) -> I2cReply {
        self.finish_conversion(now_ns);
        if self.holds_sda() {
            return I2cReply::Stuck;
        }
        match step {
            I2cStep::Start => {
                if self.bus != Bus::AwaitingStop {
                    self.bus = Bus::Idle;
                }
                I2cReply::Ack
            }
            I2cStep::Stop => {
                self.bus = Bus::Idle;
                I2cReply::Ack
            }
            I2cStep::Address { addr, read } => self.address(addr, read, now_ns),
            I2cStep::Write(byte) => match self.bus {
                Bus::Command => {
                    self.command(byte, now_ns);
                    I2cReply::Ack
                }
                _ => I2cReply::Nack,
            },
            I2cStep::Read { ack } => match self.bus {
                Bus::Reading { bytes, len, next } => {
                    let byte = bytes.get(usize::from(next)).copied().unwrap_or(0xFF);
                    self.bus = if ack && next + 1 < len {
                        Bus::Reading {
                            bytes,
                            len,
                            next: next + 1,
                        }
                    } else {
                        Bus::Ignoring
                    };
                    I2cReply::Data(byte)
                }
                // Nobody drives SDA: the pull-ups read 0xFF.
                _ => I2cReply::Data(0xFF),
            },
        }
    }

    fn address(&mut self, addr: u8, read: bool, now_ns: u64) -> I2cReply {
        if addr != ADDRESS || self.bus == Bus::AwaitingStop || now_ns < self.busy_until_ns {
            self.bus = Bus::Ignoring;
            return I2cReply::Nack;
        }
        self.bus = if read {
            let bytes = match self.pending_read {
                PendingRead::Adc => {
                    // 0 when nothing finished since the last read, or while converting.
                    let v = if self.conversion.is_some() {
                        0
                    } else {
                        self.adc.take().unwrap_or(0)
                    };
                    let [_, a, b, c] = v.to_be_bytes();
                    ([a, b, c], 3)
                }
                PendingRead::Prom(word) => {
                    let [h, l] = prom()
                        .get(usize::from(word))
                        .copied()
                        .unwrap_or(0)
                        .to_be_bytes();
                    ([h, l, 0], 2)
                }
            };
            Bus::Reading {
                bytes: bytes.0,
                len: bytes.1,
                next: 0,
            }
        } else {
            Bus::Command
        };
        I2cReply::Ack
    }

    fn command(&mut self, byte: u8, now_ns: u64) {
        match byte {
            0x1E => {
                self.conversion = None;
                self.adc = None;
                self.busy_until_ns = now_ns + RESET_NS;
            }
            0x40..=0x48 | 0x50..=0x58 if byte & 1 == 0 => {
                let osr = usize::from((byte & 0x0F) / 2);
                let t = CONVERSION_NS.get(osr).copied().unwrap_or(9_040_000);
                self.conversion = Some(Conversion {
                    d1: byte < 0x50,
                    done_ns: now_ns + t,
                });
            }
            0x00 => self.pending_read = PendingRead::Adc,
            0xA0..=0xAE if byte & 1 == 0 => {
                self.pending_read = PendingRead::Prom((byte - 0xA0) / 2)
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A write of `command` as one transaction.
    fn command(chip: &mut Ms5611, command: u8, t: u64) -> Vec<I2cReply> {
        [
            I2cStep::Start,
            I2cStep::Address {
                addr: ADDRESS,
                read: false,
            },
            I2cStep::Write(command),
            I2cStep::Stop,
        ]
        .into_iter()
        .map(|s| chip.step(s, t))
        .collect()
    }

    /// A read of `n` bytes as one transaction.
    fn read(chip: &mut Ms5611, n: usize, t: u64) -> Vec<u8> {
        chip.step(I2cStep::Start, t);
        assert_eq!(
            chip.step(
                I2cStep::Address {
                    addr: ADDRESS,
                    read: true
                },
                t
            ),
            I2cReply::Ack
        );
        let bytes = (0..n)
            .map(|i| match chip.step(I2cStep::Read { ack: i + 1 < n }, t) {
                I2cReply::Data(b) => b,
                other => panic!("{other:?}"),
            })
            .collect();
        chip.step(I2cStep::Stop, t);
        bytes
    }

    fn adc(chip: &mut Ms5611, t: u64) -> u32 {
        command(chip, 0x00, t);
        let b = read(chip, 3, t);
        u32::from_be_bytes([0, b[0], b[1], b[2]])
    }

    #[test]
    fn prom_carries_the_calibration_and_a_valid_crc() {
        let mut chip = Ms5611::new();
        let words: Vec<u16> = (0..8u8)
            .map(|w| {
                command(&mut chip, 0xA0 + 2 * w, 0);
                let b = read(&mut chip, 2, 0);
                u16::from_be_bytes([b[0], b[1]])
            })
            .collect();
        assert_eq!(&words[1..7], &CALIBRATION);
        let words: [u16; 8] = words.try_into().unwrap();
        assert_eq!(u16::from(crc4(&words)), words[7] & 0x0F);
        // The driver's CRC (AN520) agrees.
        assert_eq!(ms5611_crc(&words), words[7] & 0x0F);
        // Only 0x77 answers.
        chip.step(I2cStep::Start, 0);
        assert_eq!(
            chip.step(
                I2cStep::Address {
                    addr: 0x76,
                    read: false
                },
                0
            ),
            I2cReply::Nack
        );
    }

    /// AN520's CRC-4 written out once more, bit by bit from the application note.
    fn ms5611_crc(words: &[u16; 8]) -> u16 {
        let mut n = *words;
        n[7] &= 0xFF00;
        let mut rem: u32 = 0;
        for cnt in 0..16 {
            rem ^= if cnt % 2 == 1 {
                u32::from(n[cnt >> 1] & 0xFF)
            } else {
                u32::from(n[cnt >> 1] >> 8)
            };
            for _ in 0..8 {
                rem = if rem & 0x8000 != 0 {
                    ((rem << 1) ^ 0x3000) & 0xFFFF
                } else {
                    (rem << 1) & 0xFFFF
                };
            }
        }
        ((rem >> 12) & 0xF) as u16
    }

    #[test]
    fn conversions_take_the_osr_time_and_read_zero_until_done() {
        let mut chip = Ms5611::new();
        chip.set_truth(0, isa_pressure_pa(500.0), 25.0);
        // D1 at OSR 4096 (0x48): 9.04 ms.
        command(&mut chip, 0x48, 1_000);
        assert_eq!(adc(&mut chip, 5_000_000), 0, "still converting");
        chip.set_truth(10_040_000, isa_pressure_pa(500.0), 25.0);
        let d1 = adc(&mut chip, 10_040_000);
        assert_eq!(adc(&mut chip, 10_040_000), 0, "a second read gives 0");
        // D2 at OSR 256 (0x50): 0.60 ms.
        command(&mut chip, 0x50, 20_000_000);
        let d2 = adc(&mut chip, 20_600_000);
        // The datasheet's first-order compensation reads the truth back.
        let c = CALIBRATION.map(i64::from);
        let dt = i64::from(d2) - c[4] * 256;
        let temp = 2000 + dt * c[5] / 8_388_608;
        let off = c[1] * 65_536 + c[3] * dt / 128;
        let sens = c[0] * 32_768 + c[2] * dt / 256;
        let p = (i64::from(d1) * sens / 2_097_152 - off) / 32_768;
        assert!((temp - 2500).abs() <= 1, "{temp}");
        let want = isa_pressure_pa(500.0);
        assert!((p as f64 - want).abs() <= 2.0, "{p} Pa for {want}");
        // 95 461 Pa at 500 m (ISA).
        assert!((want - 95_461.0).abs() < 1.0, "{want}");
    }

    #[test]
    fn reset_aborts_a_conversion_and_the_chip_does_not_answer_while_reloading() {
        let mut chip = Ms5611::new();
        command(&mut chip, 0x40, 0);
        command(&mut chip, 0x1E, 100_000);
        chip.step(I2cStep::Start, 1_000_000);
        assert_eq!(
            chip.step(
                I2cStep::Address {
                    addr: ADDRESS,
                    read: true
                },
                1_000_000
            ),
            I2cReply::Nack
        );
        chip.step(I2cStep::Stop, 1_000_000);
        assert_eq!(adc(&mut chip, 3_000_000), 0, "the conversion was aborted");
    }

    #[test]
    fn a_stuck_read_holds_sda_until_scl_pulses_and_a_stop() {
        let mut chip = Ms5611::new();
        chip.hold_sda_low(9);
        assert!(chip.holds_sda());
        // The controller can do nothing: START never completes.
        assert_eq!(chip.step(I2cStep::Start, 0), I2cReply::Stuck);
        assert_eq!(chip.step(I2cStep::Stop, 0), I2cReply::Stuck);
        // Eight pulses are not enough.
        for _ in 0..8 {
            chip.scl(false);
            chip.scl(true);
        }
        assert!(chip.holds_sda());
        chip.scl(false);
        chip.scl(true);
        assert!(!chip.holds_sda(), "released after the ninth");
        assert!(chip.awaits_stop());
        // Without a STOP its address goes unanswered.
        chip.step(I2cStep::Start, 0);
        assert_eq!(
            chip.step(
                I2cStep::Address {
                    addr: ADDRESS,
                    read: false
                },
                0
            ),
            I2cReply::Nack
        );
        // STOP by hand: SDA low, then released while SCL is high.
        chip.sda(false);
        chip.sda(true);
        assert!(!chip.awaits_stop());
        assert_eq!(
            command(&mut chip, 0x1E, 0),
            vec![I2cReply::Ack, I2cReply::Ack, I2cReply::Ack, I2cReply::Ack]
        );
    }
}
