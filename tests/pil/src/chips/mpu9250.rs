//! The InvenSense MPU-9250 on SPI (MPU-9250 Product Specification PS-MPU-9250A-01 rev 1.1
//! and Register Map RM-MPU-9250A-00 rev 1.6): the register file with its reset values,
//! burst access with auto-increment (first byte: bit 7 = read, bits 6:0 = address), the
//! 100 ms start-up before registers answer, PWR_MGMT_1 (H_RESET, SLEEP), PWR_MGMT_2 (axis
//! disables), the sample clock (1 kHz internal with the DLPF, 8 kHz without, 32 kHz with
//! FCHOICE_B; divided by 1 + SMPLRT_DIV) from the chip's own oscillator with its drift,
//! GYRO_CONFIG / ACCEL_CONFIG full scales, INT_PIN_CFG (ACTL, OPEN, LATCH_INT_EN,
//! INT_ANYRD_2CLEAR), INT_ENABLE RAW_RDY_EN and INT_STATUS, USER_CTRL (I2C_MST_EN,
//! SIG_COND_RST, the self-clearing resets), the sensor registers (big-endian, two's
//! complement) and the I²C master's slave 0 (SLV0_ADDR/REG/CTRL/DO, EXT_SENS_DATA), which
//! reaches the [`Ak8963`] inside the package at every sample.
//!
//! Samples are scheduled ahead by the world with the truth at their instant
//! ([`Mpu9250::schedule_sample`]) and applied when the MCU's clock reaches them, so the
//! registers change exactly at the sample time as the MCU sees it; the data-ready edges come
//! out with their times ([`Mpu9250::take_int_edges`]). Not modelled: the FIFO (FIFO_COUNT
//! reads 0), the DLPF's filtering (the internal rate follows DLPF_CFG; the samples are the
//! truth with the world's noise), wake-on-motion, cycle mode, self-test, slaves 1–4, and
//! the I²C master's bus time (EXT_SENS_DATA holds a slave's bytes at the sample itself).

use super::ak8963::{self, Ak8963};
use super::{Edge, G_MPS2};

/// WHO_AM_I of the MPU-9250.
pub const WHO_AM_I_VALUE: u8 = 0x71;
/// From power-on until registers can be read and written (PS §3.1 "start-up time for
/// register read/write", 100 ms).
pub const START_UP_NS: u64 = 100_000_000;
/// Data-ready pulse length with LATCH_INT_EN = 0 (RM, INT_PIN_CFG: "50 µs pulse").
pub const INT_PULSE_NS: u64 = 50_000;
/// Gyro sensitivity per GYRO_FS_SEL (±250, 500, 1000, 2000 °/s), LSB per °/s, as PS table 1
/// gives it (131, 65.5, 32.8, 16.4: rounded from 32 768 / full scale, so a driver scaling by
/// full scale / 32 768 is 0.1 % off at 1000 and 2000 °/s, as on the silicon).
pub const GYRO_LSB_PER_DPS: [f64; 4] = [131.0, 65.5, 32.8, 16.4];
/// Accelerometer sensitivity per ACCEL_FS_SEL (±2, 4, 8, 16 g), LSB per g (PS table 2).
pub const ACCEL_LSB_PER_G: [f64; 4] = [16_384.0, 8_192.0, 4_096.0, 2_048.0];
/// Temperature sensitivity, LSB per °C (PS table 3: 333.87), and the output's 21 °C zero.
pub const TEMP_LSB_PER_C: f64 = 333.87;
/// Room temperature offset: TEMP_OUT is 0 at 21 °C.
pub const TEMP_ZERO_C: f64 = 21.0;

const SMPLRT_DIV: u8 = 0x19;
const CONFIG: u8 = 0x1A;
const GYRO_CONFIG: u8 = 0x1B;
const ACCEL_CONFIG: u8 = 0x1C;
const I2C_SLV0_ADDR: u8 = 0x25;
const I2C_SLV0_REG: u8 = 0x26;
const I2C_SLV0_CTRL: u8 = 0x27;
const I2C_MST_STATUS: u8 = 0x36;
const INT_PIN_CFG: u8 = 0x37;
const INT_ENABLE: u8 = 0x38;
const INT_STATUS: u8 = 0x3A;
const ACCEL_XOUT_H: u8 = 0x3B;
const TEMP_OUT_H: u8 = 0x41;
const GYRO_XOUT_H: u8 = 0x43;
const EXT_SENS_DATA_00: u8 = 0x49;
const I2C_SLV0_DO: u8 = 0x63;
const USER_CTRL: u8 = 0x6A;
const PWR_MGMT_1: u8 = 0x6B;
const PWR_MGMT_2: u8 = 0x6C;
const FIFO_COUNTH: u8 = 0x72;
const WHO_AM_I: u8 = 0x75;

/// Registers the MCU cannot write (RM: R only).
fn read_only(register: u8) -> bool {
    matches!(
        register,
        I2C_MST_STATUS | INT_STATUS..=0x60 | FIFO_COUNTH | 0x73 | WHO_AM_I
    )
}

/// One sample of the truth at the chip, in the accelerometer/gyro axes of the package
/// (the board has applied its mounting).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Measurement {
    /// Specific force, m/s² (+1 g on z lying flat, face up).
    pub accel_mps2: [f64; 3],
    /// Angular rate, °/s.
    pub gyro_dps: [f64; 3],
    /// Magnetic field, µT (the AK8963 sees it in its own axes).
    pub mag_ut: [f64; 3],
    /// Die temperature, °C.
    pub temp_c: f64,
}

/// The package's magnetometer axes from its accelerometer axes (PS §9.1 figure "Orientation
/// of axes of sensitivity": the AK8963's X is the accelerometer's Y, its Y the X, its Z the
/// −Z).
pub fn to_ak8963_axes(v: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = v;
    [y, x, -z]
}

/// The SPI transaction in progress.
#[derive(Debug, Clone, Copy, Default)]
struct Transaction {
    address: Option<u8>,
    read: bool,
    /// A read cleared the interrupt status already (INT_ANYRD_2CLEAR: once per read).
    cleared: bool,
}

/// The chip.
#[derive(Debug, Clone)]
pub struct Mpu9250 {
    regs: [u8; 128],
    spi: Option<Transaction>,
    /// Registers answer from here on, ns.
    ready_ns: u64,
    /// The sample clock: the last sample's instant, ns.
    last_sample_ns: u64,
    /// Samples scheduled but not yet reached by the MCU's clock, in time order.
    pending: Vec<(u64, Measurement)>,
    /// The field the AK8963 measures (the latest sample's).
    field_ut: [f64; 3],
    ak: Ak8963,
    /// INT asserted (logical: the data-ready interrupt is up).
    int_up: bool,
    int_edges: Vec<Edge>,
    /// The chip's oscillator runs this much fast, ppm.
    drift_ppm: f64,
    samples: u64,
    /// The latest sample's data was read (a sensor register read since it landed).
    read_since_sample: bool,
    /// Samples that landed with the previous one never read.
    missed: u64,
    /// The previous sample raised data-ready (only those can be missed).
    signalled: bool,
}

impl Mpu9250 {
    /// A chip powered on at `now_ns`, its oscillator `drift_ppm` fast (the AK8963 on its own
    /// oscillator, `ak_drift_ppm`).
    pub fn new(now_ns: u64, drift_ppm: f64, ak_drift_ppm: f64) -> Self {
        let mut chip = Self {
            regs: [0; 128],
            spi: None,
            ready_ns: now_ns + START_UP_NS,
            last_sample_ns: now_ns + START_UP_NS,
            pending: Vec::new(),
            field_ut: [0.0; 3],
            ak: Ak8963::new(ak_drift_ppm),
            int_up: false,
            int_edges: Vec::new(),
            drift_ppm,
            samples: 0,
            read_since_sample: true,
            missed: 0,
            signalled: false,
        };
        chip.reset_registers();
        chip
    }

    /// RM "Register Map": every register 0x00 except PWR_MGMT_1 (0x01) and WHO_AM_I (0x71).
    fn reset_registers(&mut self) {
        self.regs = [0; 128];
        self.set(PWR_MGMT_1, 0x01);
        self.set(WHO_AM_I, WHO_AM_I_VALUE);
    }

    fn reg(&self, register: u8) -> u8 {
        self.regs.get(usize::from(register)).copied().unwrap_or(0)
    }

    fn set(&mut self, register: u8, value: u8) {
        if let Some(r) = self.regs.get_mut(usize::from(register)) {
            *r = value;
        }
    }

    /// Samples the chip has taken so far.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Samples whose data no one read before the next one replaced it (the MCU missed
    /// them).
    pub fn samples_missed(&self) -> u64 {
        self.missed
    }

    /// The sample clock ticks with no sample (a stalled sensor: no data, no data-ready).
    pub fn skip_sample(&mut self) {
        if let Some(t) = self.next_sample_ns() {
            self.last_sample_ns = t;
        }
    }

    fn sleeping(&self) -> bool {
        self.reg(PWR_MGMT_1) & 0x40 != 0
    }

    /// The internal sample rate before SMPLRT_DIV, Hz (RM, SMPLRT_DIV and CONFIG): 32 kHz
    /// when FCHOICE_B bypasses the DLPF, 8 kHz with DLPF_CFG 0 or 7, else 1 kHz.
    pub fn internal_rate_hz(&self) -> u32 {
        let fchoice_b = self.reg(GYRO_CONFIG) & 0x03;
        let dlpf = self.reg(CONFIG) & 0x07;
        if fchoice_b != 0 {
            32_000
        } else if dlpf == 0 || dlpf == 7 {
            8_000
        } else {
            1_000
        }
    }

    /// The sample period by the chip's own clock, ns: (1 + SMPLRT_DIV) / internal rate,
    /// shortened by the oscillator's drift. SMPLRT_DIV only applies with the DLPF on (RM:
    /// "only effective when FCHOICE = 2'b11 … and 0 < DLPF_CFG < 7").
    pub fn sample_period_ns(&self) -> u64 {
        let rate = self.internal_rate_hz();
        let div = if rate == 1_000 {
            u64::from(self.reg(SMPLRT_DIV)) + 1
        } else {
            1
        };
        let nominal = 1_000_000_000 * div / u64::from(rate);
        (nominal as f64 / (1.0 + self.drift_ppm * 1e-6)).round() as u64
    }

    /// The next sample's instant, ns (None while asleep), for the world to schedule it.
    pub fn next_sample_ns(&self) -> Option<u64> {
        (!self.sleeping()).then(|| self.last_sample_ns + self.sample_period_ns())
    }

    /// The sample due at [`Mpu9250::next_sample_ns`] with the truth `m` at that instant:
    /// kept until the MCU's clock reaches it; the data-ready edge (and with a pulse its end)
    /// is queued now with its time.
    pub fn schedule_sample(&mut self, m: Measurement) {
        let Some(t) = self.next_sample_ns() else {
            return;
        };
        self.last_sample_ns = t;
        // Bounded: an MCU that never reads still sees the samples applied in order.
        while self.pending.len() >= 2 {
            let (t0, m0) = self.pending.remove(0);
            self.apply_sample(t0, m0);
        }
        self.pending.push((t, m));
        if self.reg(INT_ENABLE) & 0x01 != 0 {
            self.raise_int(t);
        }
    }

    fn cfg(&self) -> u8 {
        self.reg(INT_PIN_CFG)
    }

    fn raise_int(&mut self, t: u64) {
        let latched = self.cfg() & 0x20 != 0;
        if !self.int_up {
            self.int_up = true;
            self.int_edges.push((t, self.int_level()));
        }
        if !latched {
            self.int_up = false;
            self.int_edges.push((t + INT_PULSE_NS, self.int_level()));
        }
    }

    /// The INT pin's electrical level (ACTL: active low when set); with OPEN set the chip
    /// only pulls it low, so released it is whatever the board's pull makes it.
    pub fn int_level(&self) -> bool {
        let active_low = self.cfg() & 0x80 != 0;
        self.int_up != active_low
    }

    /// Whether the INT pin is open-drain (INT_PIN_CFG OPEN).
    pub fn int_open_drain(&self) -> bool {
        self.cfg() & 0x40 != 0
    }

    /// INT's changes since the last call, (time ns, electrical level), in time order.
    pub fn take_int_edges(&mut self) -> Vec<Edge> {
        std::mem::take(&mut self.int_edges)
    }

    /// Applies everything due by `now_ns`: samples and the AK8963's measurements, in time
    /// order.
    fn catch_up(&mut self, now_ns: u64) {
        loop {
            let sample = self
                .pending
                .first()
                .map(|(t, _)| *t)
                .filter(|t| *t <= now_ns);
            let mag = self.ak.next_measurement_ns().filter(|t| *t <= now_ns);
            match (sample, mag) {
                (Some(s), m) if m.is_none_or(|m| s <= m) => {
                    let (t, meas) = self.pending.remove(0);
                    self.apply_sample(t, meas);
                }
                (_, Some(m)) => self.ak.measure(m, to_ak8963_axes(self.field_ut)),
                _ => return,
            }
        }
    }

    fn apply_sample(&mut self, t: u64, m: Measurement) {
        self.samples += 1;
        if self.signalled && !self.read_since_sample {
            self.missed += 1;
        }
        self.read_since_sample = false;
        self.signalled = self.reg(INT_ENABLE) & 0x01 != 0;
        self.field_ut = m.mag_ut;
        // Measurements the AK8963 finished before this sample see the previous field.
        while let Some(mt) = self.ak.next_measurement_ns().filter(|mt| *mt <= t) {
            self.ak.measure(mt, to_ak8963_axes(m.mag_ut));
        }
        let scale = |register: u8| usize::from((self.reg(register) >> 3) & 3);
        let gyro_lsb = GYRO_LSB_PER_DPS
            .get(scale(GYRO_CONFIG))
            .copied()
            .unwrap_or(16.4);
        let accel_lsb = ACCEL_LSB_PER_G
            .get(scale(ACCEL_CONFIG))
            .copied()
            .unwrap_or(2_048.0);
        let disabled = self.reg(PWR_MGMT_2);
        let counts = |v: f64, lsb: f64| (v * lsb).round().clamp(-32_768.0, 32_767.0) as i16;
        for (i, a) in m.accel_mps2.iter().enumerate() {
            // DISABLE_XA..ZA: bits 5..3.
            let off = disabled & (0x20 >> i) != 0;
            let c = if off {
                0
            } else {
                counts(a / G_MPS2, accel_lsb)
            };
            self.set_word(ACCEL_XOUT_H + 2 * i as u8, c);
        }
        let temp = counts(m.temp_c - TEMP_ZERO_C, TEMP_LSB_PER_C);
        self.set_word(TEMP_OUT_H, temp);
        for (i, g) in m.gyro_dps.iter().enumerate() {
            // DISABLE_XG..ZG: bits 2..0.
            let off = disabled & (0x04 >> i) != 0;
            let c = if off { 0 } else { counts(*g, gyro_lsb) };
            self.set_word(GYRO_XOUT_H + 2 * i as u8, c);
        }
        self.run_slave0(t);
        // RAW_DATA_RDY_INT latches whether or not it drives the pin.
        let status = self.reg(INT_STATUS) | 0x01;
        self.set(INT_STATUS, status);
    }

    fn set_word(&mut self, high: u8, value: i16) {
        let [h, l] = value.to_be_bytes();
        self.set(high, h);
        self.set(high + 1, l);
    }

    /// The I²C master's slave 0 at a sample (USER_CTRL I2C_MST_EN and SLV0_EN): a read of
    /// SLV0_LENG bytes from SLV0_REG into EXT_SENS_DATA_00.., or a write of SLV0_DO; a slave
    /// address nobody answers sets I2C_SLV0_NACK.
    fn run_slave0(&mut self, t: u64) {
        let ctrl = self.reg(I2C_SLV0_CTRL);
        if self.reg(USER_CTRL) & 0x20 == 0 || ctrl & 0x80 == 0 {
            return;
        }
        let addr = self.reg(I2C_SLV0_ADDR);
        let read = addr & 0x80 != 0;
        let start = self.reg(I2C_SLV0_REG);
        if addr & 0x7F != ak8963::ADDRESS {
            let status = self.reg(I2C_MST_STATUS) | 0x01;
            self.set(I2C_MST_STATUS, status);
            return;
        }
        if read {
            for k in 0..(ctrl & 0x0F) {
                let byte = self.ak.read(start.wrapping_add(k));
                self.set(EXT_SENS_DATA_00 + k, byte);
            }
        } else {
            let value = self.reg(I2C_SLV0_DO);
            self.ak.write(start, value, t);
        }
    }

    /// nCS falls at `now_ns`: a transaction starts.
    pub fn select(&mut self, now_ns: u64) {
        self.catch_up(now_ns);
        self.spi = Some(Transaction::default());
    }

    /// nCS rises: the transaction ends.
    pub fn deselect(&mut self) {
        self.spi = None;
    }

    /// One byte clocked at `now_ns` while selected: MOSI in, MISO out (`None`: SDO not
    /// driven — deselected, or before the start-up time).
    pub fn byte(&mut self, mosi: u8, now_ns: u64) -> Option<u8> {
        self.catch_up(now_ns);
        let mut tx = self.spi?;
        let ready = now_ns >= self.ready_ns;
        let Some(address) = tx.address else {
            tx.address = Some(mosi & 0x7F);
            tx.read = mosi & 0x80 != 0;
            self.spi = Some(tx);
            return ready.then_some(0x00);
        };
        tx.address = Some((address + 1) & 0x7F);
        if !ready {
            self.spi = Some(tx);
            return None;
        }
        let miso = if tx.read {
            let value = self.reg(address);
            if (ACCEL_XOUT_H..EXT_SENS_DATA_00 + 24).contains(&address) {
                self.read_since_sample = true;
            }
            let any_read_clears = self.cfg() & 0x10 != 0;
            if (any_read_clears && !tx.cleared) || address == INT_STATUS {
                tx.cleared = true;
                self.clear_interrupt(now_ns);
            }
            value
        } else {
            self.write(address, mosi, now_ns);
            0x00
        };
        self.spi = Some(tx);
        Some(miso)
    }

    fn clear_interrupt(&mut self, now_ns: u64) {
        self.set(INT_STATUS, 0);
        if self.int_up {
            self.int_up = false;
            self.int_edges.push((now_ns, self.int_level()));
        }
    }

    fn write(&mut self, address: u8, value: u8, now_ns: u64) {
        if read_only(address) {
            return;
        }
        match address {
            PWR_MGMT_1 if value & 0x80 != 0 => {
                // H_RESET: every register to its reset value; the bit clears itself.
                let level = self.int_level();
                self.reset_registers();
                self.int_up = false;
                if self.int_level() != level {
                    self.int_edges.push((now_ns, self.int_level()));
                }
                self.ak = Ak8963::new(0.0);
                self.last_sample_ns = now_ns;
            }
            PWR_MGMT_1 => {
                let was_asleep = self.sleeping();
                self.set(address, value);
                if was_asleep && !self.sleeping() {
                    self.last_sample_ns = now_ns;
                }
            }
            USER_CTRL => {
                // FIFO_RST, I2C_MST_RST and SIG_COND_RST clear themselves; SIG_COND_RST also
                // clears the sensor registers.
                if value & 0x01 != 0 {
                    for r in ACCEL_XOUT_H..EXT_SENS_DATA_00 {
                        self.set(r, 0);
                    }
                }
                self.set(address, value & !0x07);
            }
            INT_PIN_CFG => {
                let level = self.int_level();
                self.set(address, value);
                if self.int_level() != level {
                    self.int_edges.push((now_ns, self.int_level()));
                }
            }
            _ => self.set(address, value),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(chip: &mut Mpu9250, t: u64, register: u8, value: u8) {
        chip.select(t);
        chip.byte(register, t);
        chip.byte(value, t);
        chip.deselect();
    }

    fn read(chip: &mut Mpu9250, t: u64, register: u8, n: usize) -> Vec<u8> {
        chip.select(t);
        chip.byte(0x80 | register, t);
        let out = (0..n).map(|_| chip.byte(0, t).unwrap_or(0xEE)).collect();
        chip.deselect();
        out
    }

    fn word(b: &[u8], at: usize) -> i16 {
        i16::from_be_bytes([b[at], b[at + 1]])
    }

    #[test]
    fn silent_during_start_up_then_reset_values() {
        let mut chip = Mpu9250::new(0, 0.0, 0.0);
        chip.select(50_000_000);
        assert_eq!(chip.byte(0x80 | WHO_AM_I, 50_000_000), None);
        chip.deselect();
        let t = START_UP_NS;
        assert_eq!(read(&mut chip, t, WHO_AM_I, 1), vec![0x71]);
        assert_eq!(read(&mut chip, t, PWR_MGMT_1, 1), vec![0x01]);
        assert_eq!(read(&mut chip, t, SMPLRT_DIV, 2), vec![0, 0]);
        // Not selected: nothing on SDO.
        assert_eq!(chip.byte(0x80 | WHO_AM_I, t), None);
    }

    #[test]
    fn sample_rate_follows_dlpf_and_divider_on_its_own_clock() {
        let mut chip = Mpu9250::new(0, 0.0, 0.0);
        let t = START_UP_NS;
        // Reset: DLPF_CFG 0 → 8 kHz, divider ignored.
        assert_eq!(chip.internal_rate_hz(), 8_000);
        assert_eq!(chip.sample_period_ns(), 125_000);
        write(&mut chip, t, CONFIG, 0x01);
        write(&mut chip, t, SMPLRT_DIV, 1);
        assert_eq!(chip.sample_period_ns(), 2_000_000, "1 kHz / 2");
        write(&mut chip, t, GYRO_CONFIG, 0x01);
        assert_eq!(
            chip.internal_rate_hz(),
            32_000,
            "FCHOICE_B bypasses the DLPF"
        );
        let fast = Mpu9250::new(0, 500.0, 0.0);
        let mut fast = fast;
        write(&mut fast, t, CONFIG, 0x01);
        // 500 ppm fast: 1 ms becomes 999.5 µs.
        assert_eq!(fast.sample_period_ns(), 999_500);
        // Asleep: no samples.
        write(&mut chip, t, PWR_MGMT_1, 0x40);
        assert_eq!(chip.next_sample_ns(), None);
    }

    #[test]
    fn samples_appear_at_their_instant_in_the_configured_units() {
        let mut chip = Mpu9250::new(0, 0.0, 0.0);
        let t = START_UP_NS;
        write(&mut chip, t, CONFIG, 0x01);
        write(&mut chip, t, GYRO_CONFIG, 3 << 3); // ±2000 °/s
        write(&mut chip, t, ACCEL_CONFIG, 2 << 3); // ±8 g
        let due = chip.next_sample_ns().unwrap();
        assert_eq!(due, t + 1_000_000);
        chip.schedule_sample(Measurement {
            accel_mps2: [0.0, G_MPS2 * 0.5, G_MPS2],
            gyro_dps: [100.0, -250.0, 0.0],
            mag_ut: [0.0; 3],
            temp_c: 31.0,
        });
        // Before its instant the registers still hold nothing.
        let before = read(&mut chip, due - 1, ACCEL_XOUT_H, 14);
        assert!(before.iter().all(|&b| b == 0));
        let b = read(&mut chip, due, ACCEL_XOUT_H, 14);
        assert_eq!(word(&b, 0), 0);
        assert_eq!(word(&b, 2), 2_048, "0.5 g at 4096 LSB/g");
        assert_eq!(word(&b, 4), 4_096);
        assert_eq!(word(&b, 6), 3_339, "10 °C above 21 °C at 333.87 LSB/°C");
        assert_eq!(word(&b, 8), 1_640, "100 °/s at 16.4 LSB/(°/s)");
        assert_eq!(word(&b, 10), -4_100);
        // Clipping at full scale.
        chip.schedule_sample(Measurement {
            gyro_dps: [5_000.0, 0.0, 0.0],
            ..Measurement::default()
        });
        let b = read(&mut chip, due + 1_000_000, GYRO_XOUT_H, 2);
        assert_eq!(word(&b, 0), 32_767);
        assert_eq!(chip.samples(), 2);
    }

    #[test]
    fn data_ready_pulses_50us_or_latches_until_a_read() {
        let mut chip = Mpu9250::new(0, 0.0, 0.0);
        let t = START_UP_NS;
        write(&mut chip, t, CONFIG, 0x01);
        write(&mut chip, t, INT_ENABLE, 0x01);
        chip.schedule_sample(Measurement::default());
        let due = t + 1_000_000;
        assert_eq!(
            chip.take_int_edges(),
            vec![(due, true), (due + INT_PULSE_NS, false)]
        );
        // INT_STATUS latched regardless; reading it clears it.
        assert_eq!(read(&mut chip, due + 100_000, INT_STATUS, 1), vec![0x01]);
        assert_eq!(read(&mut chip, due + 100_000, INT_STATUS, 1), vec![0x00]);
        // Latched, any read clears (the project's driver: INT_PIN_CFG 0x30).
        write(&mut chip, due, INT_PIN_CFG, 0x30);
        chip.schedule_sample(Measurement::default());
        let due2 = due + 1_000_000;
        assert_eq!(chip.take_int_edges(), vec![(due2, true)]);
        read(&mut chip, due2 + 20_000, ACCEL_XOUT_H, 6);
        assert_eq!(chip.take_int_edges(), vec![(due2 + 20_000, false)]);
        // Active low: the level inverts.
        write(&mut chip, due2 + 30_000, INT_PIN_CFG, 0xB0);
        assert_eq!(chip.take_int_edges(), vec![(due2 + 30_000, true)]);
        assert!(chip.int_level());
        // No RAW_RDY_EN: no edge, but the status still latches.
        write(&mut chip, due2 + 40_000, INT_ENABLE, 0x00);
        chip.schedule_sample(Measurement::default());
        assert!(chip.take_int_edges().is_empty());
        assert_eq!(read(&mut chip, due2 + 1_000_000, INT_STATUS, 1), vec![0x01]);
    }

    #[test]
    fn h_reset_restores_defaults_and_writes_to_read_only_registers_are_ignored() {
        let mut chip = Mpu9250::new(0, 0.0, 0.0);
        let t = START_UP_NS;
        write(&mut chip, t, SMPLRT_DIV, 7);
        write(&mut chip, t, WHO_AM_I, 0x00);
        assert_eq!(read(&mut chip, t, WHO_AM_I, 1), vec![0x71]);
        write(&mut chip, t, PWR_MGMT_1, 0x80);
        assert_eq!(read(&mut chip, t, SMPLRT_DIV, 1), vec![0]);
        assert_eq!(read(&mut chip, t, PWR_MGMT_1, 1), vec![0x01]);
        // A burst write auto-increments.
        chip.select(t);
        for b in [SMPLRT_DIV, 4, 0x03, 0x18] {
            chip.byte(b, t);
        }
        chip.deselect();
        assert_eq!(read(&mut chip, t, SMPLRT_DIV, 3), vec![4, 0x03, 0x18]);
    }

    #[test]
    fn slave0_reads_the_ak8963_at_every_sample() {
        let mut chip = Mpu9250::new(0, 0.0, 0.0);
        let mut t = START_UP_NS;
        write(&mut chip, t, CONFIG, 0x01);
        write(&mut chip, t, USER_CTRL, 0x20);
        // Write CNTL1 = continuous 100 Hz, 16-bit through slave 0.
        write(&mut chip, t, I2C_SLV0_ADDR, ak8963::ADDRESS);
        write(&mut chip, t, I2C_SLV0_REG, 0x0A);
        write(&mut chip, t, I2C_SLV0_DO, 0x16);
        write(&mut chip, t, I2C_SLV0_CTRL, 0x81);
        let field = [20.0, -5.0, 40.0];
        let m = Measurement {
            mag_ut: field,
            ..Measurement::default()
        };
        chip.schedule_sample(m);
        t += 1_000_000;
        read(&mut chip, t, WHO_AM_I, 1);
        // Then read ST1..ST2 (8 bytes) with every sample.
        write(&mut chip, t, I2C_SLV0_ADDR, 0x80 | ak8963::ADDRESS);
        write(&mut chip, t, I2C_SLV0_REG, 0x02);
        write(&mut chip, t, I2C_SLV0_CTRL, 0x88);
        // The measurement ends 7.2 ms after the first CNTL1 write (at the first sample), so
        // the slave's read at the 8th sample after the switch is the first to see DRDY; the
        // ST2 it reads ends the AK8963's read, so the next sample's ST1 is clear again.
        for _ in 0..8 {
            chip.schedule_sample(m);
        }
        t += 8_000_000;
        let ext = read(&mut chip, t, EXT_SENS_DATA_00, 8);
        assert_eq!(ext[0] & 1, 1, "ST1 DRDY after the 7.2 ms measurement");
        chip.schedule_sample(m);
        let next = read(&mut chip, t + 1_000_000, EXT_SENS_DATA_00, 1);
        assert_eq!(next[0] & 1, 0, "read already");
        t += 1_000_000;
        // The AK8963's X is the package's Y.
        let hx = i16::from_le_bytes([ext[1], ext[2]]);
        let adjust = (f64::from(ak8963::ASA[0]) - 128.0) / 256.0 + 1.0;
        assert!(
            (f64::from(hx) * adjust * 0.15 - field[1]).abs() < 0.2,
            "{hx}"
        );
        let hz = i16::from_le_bytes([ext[5], ext[6]]);
        let adjust_z = (f64::from(ak8963::ASA[2]) - 128.0) / 256.0 + 1.0;
        assert!(
            (f64::from(hz) * adjust_z * 0.15 + field[2]).abs() < 0.2,
            "{hz}"
        );
        assert_eq!(ext[7], 0x10, "ST2: BITM 16-bit");
        // A slave address nobody answers: NACK in I2C_MST_STATUS.
        write(&mut chip, t, I2C_SLV0_ADDR, 0x80 | 0x0D);
        chip.schedule_sample(m);
        let status = read(&mut chip, t + 1_000_000, I2C_MST_STATUS, 1);
        assert_eq!(status[0] & 1, 1);
    }
}
