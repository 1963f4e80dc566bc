//! The AK8963 magnetometer inside the MPU-9250 (AK8963C datasheet, register map §8 and
//! modes §6.4), as its I²C slave at 0x0C: WIA, INFO, ST1 (DRDY, DOR), HXL…HZH
//! (little-endian), ST2 (HOFL, BITM), CNTL1 (mode, 14/16-bit output), CNTL2 (soft reset) and
//! the fuse ROM's sensitivity adjustment (ASAX…ASAZ, readable only in fuse-ROM mode).
//! Measurements in continuous modes 1 (8 Hz) and 2 (100 Hz) and single measurement (7.2 ms)
//! come from the field the board gives it, in the AK8963's own axes.

/// The AK8963's I²C address.
pub const ADDRESS: u8 = 0x0C;
/// WIA: device ID of AKM.
pub const WIA_VALUE: u8 = 0x48;
/// INFO (device information for AKM use; any value).
const INFO_VALUE: u8 = 0x9A;
/// Sensitivity adjustment values burnt into this chip's fuse ROM (datasheet §8.3.11: each
/// axis's own, around 128–200).
pub const ASA: [u8; 3] = [176, 177, 165];
/// Output resolution, µT per LSB: 16-bit and 14-bit output.
pub const UT_PER_LSB_16: f64 = 0.15;
/// 14-bit output.
pub const UT_PER_LSB_14: f64 = 0.6;
/// Measurement time of one measurement (single or continuous), ns (datasheet: 7.2 ms typ.).
pub const MEASUREMENT_NS: u64 = 7_200_000;
/// Magnetic sensor overflow: |X| + |Y| + |Z| beyond this is flagged (µT).
pub const OVERFLOW_UT: f64 = 4_912.0;

const ST1: u8 = 0x02;
const HXL: u8 = 0x03;
const ST2: u8 = 0x09;
const CNTL1: u8 = 0x0A;
const CNTL2: u8 = 0x0B;
const ASAX: u8 = 0x10;

/// The operating mode (CNTL1 MODE, bits 3:0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// 0000: power-down.
    PowerDown,
    /// 0001: one measurement, then power-down.
    Single,
    /// 0010: continuous measurement 1, 8 Hz.
    Continuous8Hz,
    /// 0110: continuous measurement 2, 100 Hz.
    Continuous100Hz,
    /// 1111: fuse ROM access.
    FuseRom,
    /// Any other code (self-test, external trigger: not modelled, measure nothing).
    Other(u8),
}

impl Mode {
    fn from_bits(bits: u8) -> Self {
        match bits & 0x0F {
            0x0 => Mode::PowerDown,
            0x1 => Mode::Single,
            0x2 => Mode::Continuous8Hz,
            0x6 => Mode::Continuous100Hz,
            0xF => Mode::FuseRom,
            other => Mode::Other(other),
        }
    }

    fn period_ns(self) -> Option<u64> {
        match self {
            Mode::Continuous8Hz => Some(125_000_000),
            Mode::Continuous100Hz => Some(10_000_000),
            _ => None,
        }
    }
}

/// The chip.
#[derive(Debug, Clone)]
pub struct Ak8963 {
    cntl1: u8,
    /// HXL…HZH as the last measurement left them.
    data: [u8; 6],
    drdy: bool,
    dor: bool,
    hofl: bool,
    /// The data registers are locked between a read of ST1 (DRDY set) and of ST2.
    reading: bool,
    /// The measurement finished while locked, waiting for ST2.
    pending: Option<([u8; 6], bool)>,
    next_measurement_ns: Option<u64>,
    /// The chip's clock runs this much fast, ppm.
    drift_ppm: f64,
}

impl Ak8963 {
    /// A chip after power-on: power-down mode, nothing measured; its oscillator `drift_ppm`
    /// off.
    pub fn new(drift_ppm: f64) -> Self {
        Self {
            cntl1: 0,
            data: [0; 6],
            drdy: false,
            dor: false,
            hofl: false,
            reading: false,
            pending: None,
            next_measurement_ns: None,
            drift_ppm,
        }
    }

    /// The mode CNTL1 sets.
    pub fn mode(&self) -> Mode {
        Mode::from_bits(self.cntl1)
    }

    fn sixteen_bit(&self) -> bool {
        self.cntl1 & 0x10 != 0
    }

    fn scaled(&self, ns: u64) -> u64 {
        (ns as f64 / (1.0 + self.drift_ppm * 1e-6)).round() as u64
    }

    /// When the next measurement completes, ns (None: not measuring).
    pub fn next_measurement_ns(&self) -> Option<u64> {
        self.next_measurement_ns
    }

    /// A register read over I²C (auto-increment is the caller's).
    pub fn read(&mut self, register: u8) -> u8 {
        match register {
            0x00 => WIA_VALUE,
            0x01 => INFO_VALUE,
            ST1 => {
                if self.drdy {
                    self.reading = true;
                }
                u8::from(self.drdy) | (u8::from(self.dor) << 1)
            }
            HXL..=0x08 => self
                .data
                .get(usize::from(register - HXL))
                .copied()
                .unwrap_or(0),
            ST2 => {
                // Reading ST2 ends the read: DRDY and DOR clear and a measurement that came
                // in meanwhile is published.
                let st2 = (u8::from(self.hofl) << 3) | (self.cntl1 & 0x10);
                self.drdy = false;
                self.dor = false;
                self.reading = false;
                if let Some((data, hofl)) = self.pending.take() {
                    self.publish(data, hofl);
                }
                st2
            }
            CNTL1 => self.cntl1,
            CNTL2 => 0,
            ASAX..=0x12 if self.mode() == Mode::FuseRom => {
                ASA.get(usize::from(register - ASAX)).copied().unwrap_or(0)
            }
            _ => 0,
        }
    }

    /// A register write over I²C at `now_ns`.
    pub fn write(&mut self, register: u8, value: u8, now_ns: u64) {
        match register {
            CNTL1 => {
                self.cntl1 = value & 0x1F;
                self.next_measurement_ns = match self.mode() {
                    Mode::Single | Mode::Continuous8Hz | Mode::Continuous100Hz => {
                        Some(now_ns + self.scaled(MEASUREMENT_NS))
                    }
                    _ => None,
                };
            }
            // Soft reset: every register to its reset value.
            CNTL2 if value & 0x01 != 0 => *self = Self::new(self.drift_ppm),
            _ => {}
        }
    }

    /// A measurement due at `now_ns` completes with the field `field_ut` (the AK8963's
    /// axes, µT).
    pub fn measure(&mut self, now_ns: u64, field_ut: [f64; 3]) {
        let lsb = if self.sixteen_bit() {
            UT_PER_LSB_16
        } else {
            UT_PER_LSB_14
        };
        let limit = if self.sixteen_bit() {
            32_760.0
        } else {
            8_190.0
        };
        let hofl = field_ut.iter().map(|v| v.abs()).sum::<f64>() > OVERFLOW_UT;
        let mut data = [0u8; 6];
        for ((pair, h), asa) in data.chunks_exact_mut(2).zip(field_ut).zip(ASA) {
            // The chip reports H / adjustment (the driver multiplies it back, §8.3.11).
            let adjust = (f64::from(asa) - 128.0) * 0.5 / 128.0 + 1.0;
            let counts = (h / adjust / lsb).round().clamp(-limit, limit) as i16;
            pair.copy_from_slice(&counts.to_le_bytes());
        }
        if self.reading {
            // Data locked: the new measurement waits; DOR says one was skipped if another
            // arrives before ST2.
            if self.pending.is_some() {
                self.dor = true;
            }
            self.pending = Some((data, hofl));
        } else {
            if self.drdy {
                self.dor = true;
            }
            self.publish(data, hofl);
        }
        self.next_measurement_ns = match self.mode() {
            Mode::Single => {
                // Back to power-down after one measurement.
                self.cntl1 &= 0x10;
                None
            }
            m => m.period_ns().map(|p| now_ns + self.scaled(p)),
        };
    }

    fn publish(&mut self, data: [u8; 6], hofl: bool) {
        self.data = data;
        self.hofl = hofl;
        self.drdy = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_and_fuse_rom_only_in_fuse_mode() {
        let mut ak = Ak8963::new(0.0);
        assert_eq!(ak.read(0x00), 0x48);
        assert_eq!(ak.read(ASAX), 0, "ASA unreadable outside fuse-ROM mode");
        ak.write(CNTL1, 0x0F, 0);
        assert_eq!(ak.mode(), Mode::FuseRom);
        assert_eq!([ak.read(0x10), ak.read(0x11), ak.read(0x12)], ASA);
        assert_eq!(ak.next_measurement_ns(), None);
    }

    #[test]
    fn continuous_100hz_16bit_measures_every_10ms_with_the_adjustment_undone() {
        let mut ak = Ak8963::new(0.0);
        ak.write(CNTL1, 0x16, 1_000);
        assert_eq!(ak.mode(), Mode::Continuous100Hz);
        assert_eq!(ak.next_measurement_ns(), Some(1_000 + MEASUREMENT_NS));
        assert_eq!(ak.read(ST1), 0, "nothing measured yet");
        ak.measure(MEASUREMENT_NS + 1_000, [30.0, -15.0, 45.0]);
        assert_eq!(
            ak.next_measurement_ns(),
            Some(MEASUREMENT_NS + 1_000 + 10_000_000)
        );
        assert_eq!(ak.read(ST1) & 1, 1, "DRDY");
        let x = i16::from_le_bytes([ak.read(HXL), ak.read(HXL + 1)]);
        // The driver's Hadj = H·((ASA − 128)/256 + 1)·0.15 gives the field back.
        let adjust = (176.0 - 128.0) / 256.0 + 1.0;
        assert!((f64::from(x) * adjust * 0.15 - 30.0).abs() < 0.15, "{x}");
        let z = i16::from_le_bytes([ak.read(HXL + 4), ak.read(HXL + 5)]);
        assert!((f64::from(z) * ((165.0 - 128.0) / 256.0 + 1.0) * 0.15 - 45.0).abs() < 0.15);
        assert_eq!(ak.read(ST2), 0x10, "BITM: 16-bit output, no overflow");
        assert_eq!(ak.read(ST1), 0, "ST2 ended the read");
    }

    #[test]
    fn data_is_locked_between_st1_and_st2_and_an_overrun_is_flagged() {
        let mut ak = Ak8963::new(0.0);
        ak.write(CNTL1, 0x16, 0);
        ak.measure(7_200_000, [10.0, 0.0, 0.0]);
        assert_eq!(ak.read(ST1), 1);
        ak.measure(17_200_000, [20.0, 0.0, 0.0]);
        let first = i16::from_le_bytes([ak.read(HXL), ak.read(HXL + 1)]);
        ak.read(ST2);
        // The second measurement is published by ST2.
        assert_eq!(ak.read(ST1), 1);
        let second = i16::from_le_bytes([ak.read(HXL), ak.read(HXL + 1)]);
        assert!(second > first);
        ak.read(ST2);
        // Two measurements without a read in between: DOR.
        ak.measure(27_200_000, [0.0; 3]);
        ak.measure(37_200_000, [0.0; 3]);
        assert_eq!(ak.read(ST1), 0b11);
    }

    #[test]
    fn single_measurement_then_power_down_overflow_and_soft_reset() {
        let mut ak = Ak8963::new(0.0);
        ak.write(CNTL1, 0x01, 0);
        ak.measure(MEASUREMENT_NS, [4_000.0, 1_000.0, 0.0]);
        assert_eq!(ak.mode(), Mode::PowerDown);
        assert_eq!(ak.next_measurement_ns(), None);
        ak.read(ST1);
        assert_eq!(ak.read(ST2) & 0x08, 0x08, "HOFL beyond 4912 µT");
        ak.write(CNTL1, 0x16, 0);
        ak.write(CNTL2, 0x01, 0);
        assert_eq!(ak.mode(), Mode::PowerDown, "soft reset");
        assert_eq!(ak.read(ST1), 0);
    }

    #[test]
    fn its_own_clock_drifts() {
        let mut ak = Ak8963::new(1_000.0);
        ak.write(CNTL1, 0x16, 0);
        // 0.1 % fast: the 7.2 ms measurement ends 7.2 µs early.
        assert_eq!(ak.next_measurement_ns(), Some(7_192_807));
    }
}
