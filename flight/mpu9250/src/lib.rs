//! InvenSense MPU-9250 gyro/accelerometer over SPI (mode 3, embedded-hal-async 1.0), with
//! the AK8963 magnetometer read through the MPU's own I²C master, so one 22-byte burst read
//! returns accel, temperature, gyro and the magnetometer bytes (boards such as the Sparky2
//! leave the AUX pins unwired: Sparky 2.0 schematic, Tau Labs `flight/targets/sparky2/hw/`).
//!
//! [`Mpu9250::new`] resets, probes and configures the chip (and the AK8963 if
//! [`Config::magnetometer`]), checking a register read-back; [`Mpu9250::read`] is one burst,
//! scaled to SI units in the MPU's own axes ([`Sample`]). Delays are injected
//! ([`DelayNs`]): every wait is bounded, an absent chip is an error, never a hang, and the
//! driver runs in host tests against `embedded-hal-mock` SPI transcripts. Register map:
//! [`registers`] (RM-MPU-9250A-00 rev 1.6); ranges, filter and rate: [`config`].
//!
//! ```no_run
//! # async fn demo<S: embedded_hal_async::spi::SpiDevice>(
//! #     spi: S,
//! #     delay: &mut impl embedded_hal_async::delay::DelayNs,
//! # ) -> Result<(), mpu9250::Error<S::Error>> {
//! use mpu9250::{Config, Mpu9250};
//!
//! let mut imu = Mpu9250::new(spi, Config::default(), delay).await?;
//! // On each data-ready edge (INT is latched until any register read):
//! let sample = imu.read().await?;
//! let [gx, gy, gz] = sample.gyro_radps;
//! # let _ = (gx, gy, gz);
//! # Ok(())
//! # }
//! ```
#![cfg_attr(not(test), no_std)]
// docs.rs: the feature each gated item needs, shown beside it.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod ak8963;
pub mod config;
pub mod registers;
#[cfg(test)]
mod tests;

pub use config::{AccelRange, Config, Dlpf, GyroRange, SampleRate};

use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::spi::{Operation, SpiDevice};
use registers as reg;

/// How often WHO_AM_I is polled after the reset before the device counts as absent.
const PROBE_ATTEMPTS: u8 = 5;
/// Time allowed for the reset (RM: 100 ms start-up) and between probe attempts.
const RESET_DELAY_MS: u32 = 100;
const PROBE_DELAY_MS: u32 = 10;

/// Driver errors; `E` is the SPI error, kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The SPI transfer failed.
    Bus(E),
    /// WHO_AM_I never read 0x71/0x73: no MPU-9250 (0x00/0xFF means nothing answers).
    NotFound {
        /// The last value read.
        who_am_i: u8,
    },
    /// A configuration register did not read back what was written.
    ConfigMismatch {
        /// Register address.
        register: u8,
        /// Value read back.
        read: u8,
    },
    /// The AK8963 did not identify itself through the I²C master.
    MagnetometerNotFound {
        /// The WIA value read.
        wia: u8,
    },
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Bus(e) => write!(f, "SPI error: {e:?}"),
            Self::NotFound { who_am_i } => write!(f, "no MPU-9250 (WHO_AM_I = {who_am_i:#04x})"),
            Self::ConfigMismatch { register, read } => {
                write!(f, "register {register:#04x} read back {read:#04x}")
            }
            Self::MagnetometerNotFound { wia } => write!(f, "no AK8963 (WIA = {wia:#04x})"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for Error<E> {}

/// One scaled sample, in the MPU-9250's own axes (the board rotation is applied by the
/// firmware glue).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sample {
    /// Specific force (m/s²); the chip reads +1 g on z lying flat.
    pub accel_mps2: [f32; 3],
    /// Angular rate (rad/s).
    pub gyro_radps: [f32; 3],
    /// Die temperature (°C).
    pub temperature_c: f32,
    /// Magnetic field (µT, rotated into the MPU axes, sensitivity-adjusted) when the AK8963
    /// had a new, non-overflowed sample.
    pub mag_ut: Option<[f32; 3]>,
}

/// The driver.
#[derive(Debug)]
pub struct Mpu9250<SPI> {
    spi: SPI,
    config: Config,
    /// Per-axis AK8963 factor: µT/LSB × sensitivity adjustment (datasheet §8.3.11).
    mag_scale: [f32; 3],
}

impl<SPI: SpiDevice> Mpu9250<SPI> {
    /// Resets and configures the chip (and the AK8963 if `config.magnetometer`).
    ///
    /// # Errors
    /// [`Error::NotFound`] when WHO_AM_I stays wrong after the reset, [`Error::ConfigMismatch`]
    /// when a written register does not read back, [`Error::MagnetometerNotFound`], or
    /// [`Error::Bus`]. Every wait is a bounded `delay` call: an absent chip never hangs.
    pub async fn new(
        spi: SPI,
        config: Config,
        delay: &mut impl DelayNs,
    ) -> Result<Self, Error<SPI::Error>> {
        let mut dev = Self {
            spi,
            config,
            mag_scale: [0.0; 3],
        };
        dev.write(reg::PWR_MGMT_1, reg::H_RESET).await?;
        delay.delay_ms(RESET_DELAY_MS).await;
        dev.configure(delay).await?;
        Ok(dev)
    }

    /// Configures a chip that stayed powered across the host's reset, without the device
    /// reset and its 100 ms start-up wait: the same register writes and checks as
    /// [`Mpu9250::new`] after its reset (every one of them sets its register whole, so what
    /// the chip held before does not matter). For a host that must fly again fast — a flight
    /// controller resuming after a reset in the air; a chip that lost power needs `new`.
    ///
    /// # Errors
    /// As [`Mpu9250::new`].
    pub async fn new_warm(
        spi: SPI,
        config: Config,
        delay: &mut impl DelayNs,
    ) -> Result<Self, Error<SPI::Error>> {
        let mut dev = Self {
            spi,
            config,
            mag_scale: [0.0; 3],
        };
        dev.configure(delay).await?;
        Ok(dev)
    }

    /// Everything after the device reset: probe, configuration, the AK8963, interrupts.
    async fn configure(&mut self, delay: &mut impl DelayNs) -> Result<(), Error<SPI::Error>> {
        let config = self.config;
        let dev = self;
        dev.probe(delay).await?;
        dev.write(reg::PWR_MGMT_1, reg::CLKSEL_PLL).await?;
        dev.write(reg::PWR_MGMT_2, 0).await?;
        let user_ctrl = reg::I2C_IF_DIS
            | if config.magnetometer {
                reg::I2C_MST_EN
            } else {
                0
            };
        dev.write(reg::USER_CTRL, user_ctrl).await?;
        dev.write(reg::CONFIG, config.dlpf as u8).await?;
        dev.write(reg::SMPLRT_DIV, config.sample_rate.divider())
            .await?;
        dev.write(reg::GYRO_CONFIG, (config.gyro_range as u8) << 3)
            .await?;
        dev.write(reg::ACCEL_CONFIG, (config.accel_range as u8) << 3)
            .await?;
        dev.write(reg::ACCEL_CONFIG2, config.dlpf as u8).await?;
        // A chip that accepted the writes reads the gyro range back; a stuck bus does not.
        let read = dev.read_register(reg::GYRO_CONFIG).await?;
        if read != (config.gyro_range as u8) << 3 {
            return Err(Error::ConfigMismatch {
                register: reg::GYRO_CONFIG,
                read,
            });
        }
        if config.magnetometer {
            dev.write(reg::I2C_MST_CTRL, reg::I2C_MST_400KHZ).await?;
            dev.mag_scale = ak8963::init(dev, delay).await?;
        }
        dev.write(reg::INT_PIN_CFG, reg::INT_LATCHED_ANY_READ_CLEARS)
            .await?;
        dev.write(reg::INT_ENABLE, reg::RAW_RDY_EN).await?;
        Ok(())
    }

    /// Polls WHO_AM_I a bounded number of times.
    async fn probe(&mut self, delay: &mut impl DelayNs) -> Result<(), Error<SPI::Error>> {
        let mut who_am_i = 0;
        for attempt in 0..PROBE_ATTEMPTS {
            who_am_i = self.read_register(reg::WHO_AM_I).await?;
            if reg::WHO_AM_I_VALUES.contains(&who_am_i) {
                return Ok(());
            }
            if attempt + 1 < PROBE_ATTEMPTS {
                delay.delay_ms(PROBE_DELAY_MS).await;
            }
        }
        Err(Error::NotFound { who_am_i })
    }

    /// The configuration in use.
    #[must_use]
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// INT_STATUS (reading it also clears a latched data-ready interrupt).
    ///
    /// # Errors
    /// [`Error::Bus`].
    pub async fn interrupt_status(&mut self) -> Result<u8, Error<SPI::Error>> {
        self.read_register(reg::INT_STATUS).await
    }

    /// Reads one sample with a single burst (14 bytes, or 22 with the magnetometer).
    ///
    /// # Errors
    /// [`Error::Bus`].
    pub async fn read(&mut self) -> Result<Sample, Error<SPI::Error>> {
        let mut buf = [0u8; 22];
        // Constant ranges of a fixed-size array: checked when compiling.
        let bytes = if self.config.magnetometer {
            &mut buf[..]
        } else {
            &mut buf[..14]
        };
        self.read_registers(reg::ACCEL_XOUT_H, bytes).await?;
        Ok(self.decode(&buf))
    }

    /// Scales a burst (big-endian accel, temperature, gyro; then AK8963 ST1, 3×LE16, ST2).
    fn decode(&self, buf: &[u8; 22]) -> Sample {
        let be = |i: usize| {
            let hi = buf.get(i).copied().unwrap_or(0);
            let lo = buf.get(i + 1).copied().unwrap_or(0);
            f32::from(i16::from_be_bytes([hi, lo]))
        };
        let a = self.config.accel_range.mps2_per_lsb();
        let g = self.config.gyro_range.radps_per_lsb();
        let [
            _,
            _,
            _,
            _,
            _,
            _,
            _,
            _,
            _,
            _,
            _,
            _,
            _,
            _,
            st1,
            xl,
            xh,
            yl,
            yh,
            zl,
            zh,
            st2,
        ] = *buf;
        // RM §4.23: TEMP_degC = TEMP_OUT / 333.87 + 21.
        let temperature_c = be(6) / 333.87 + 21.0;
        let mag_ut = (self.config.magnetometer
            && st1 & 0x01 != 0
            && st2 & reg::ak8963::ST2_HOFL == 0)
            .then(|| {
                let [sx, sy, sz] = self.mag_scale;
                let m = [
                    f32::from(i16::from_le_bytes([xl, xh])) * sx,
                    f32::from(i16::from_le_bytes([yl, yh])) * sy,
                    f32::from(i16::from_le_bytes([zl, zh])) * sz,
                ];
                // AK8963 axes (PS-MPU-9250A-01 §9.1): x_mpu = y_ak, y_mpu = x_ak, z_mpu = −z_ak.
                [m[1], m[0], -m[2]]
            });
        Sample {
            accel_mps2: [be(0) * a, be(2) * a, be(4) * a],
            gyro_radps: [be(8) * g, be(10) * g, be(12) * g],
            temperature_c,
            mag_ut,
        }
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    pub(crate) async fn write(&mut self, register: u8, value: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[register, value]).await.map_err(Error::Bus)
    }

    pub(crate) async fn read_register(&mut self, register: u8) -> Result<u8, Error<SPI::Error>> {
        let mut value = [0u8];
        self.read_registers(register, &mut value).await?;
        Ok(value[0])
    }

    pub(crate) async fn read_registers(
        &mut self,
        register: u8,
        buf: &mut [u8],
    ) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [
                Operation::Write(&[register | reg::READ]),
                Operation::Read(buf),
            ])
            .await
            .map_err(Error::Bus)
    }
}
