//! TE MS5611-01BA03 barometer over I²C (embedded-hal-async 1.0): reset, PROM read with the
//! AN520 CRC-4 check, D1/D2 conversions at a chosen [`Oversampling`], first- and
//! second-order compensation and the ISA altitude ([`compensation`], pure functions).
//! The address is 0x77 with CSB low ([`ADDRESS`]; the Sparky2 ties CSB to GND and PS to VDD,
//! Tau Labs `flight/targets/sparky2/` schematic), 0x76 with CSB high.
//!
//! Delays are injected ([`DelayNs`]): the conversion waits are the datasheet's maximum
//! times, nothing polls, and the driver runs in host tests against `embedded-hal-mock` I²C
//! transcripts.
//!
//! ```no_run
//! # async fn demo<I: embedded_hal_async::i2c::I2c>(
//! #     i2c: I,
//! #     delay: &mut impl embedded_hal_async::delay::DelayNs,
//! # ) -> Result<(), ms5611::Error<I::Error>> {
//! use ms5611::{ADDRESS, Ms5611, Oversampling};
//!
//! let mut baro = Ms5611::new(i2c, ADDRESS, Oversampling::Osr1024, delay).await?;
//! let m = baro.measure(delay).await?; // 2 × 2.28 ms of conversions at OSR 1024
//! let (pa, metres) = (m.reading.pressure_pa, m.altitude_m);
//! # let _ = (pa, metres);
//! # Ok(())
//! # }
//! ```
#![cfg_attr(not(test), no_std)]
// docs.rs: the feature each gated item needs, shown beside it.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod compensation;
#[cfg(test)]
mod tests;

pub use compensation::{Prom, Reading, altitude_m};

use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::i2c::I2c;

/// Default 7-bit address (CSB tied low).
pub const ADDRESS: u8 = 0x77;

const CMD_RESET: u8 = 0x1E;
const CMD_CONVERT_D1: u8 = 0x40;
const CMD_CONVERT_D2: u8 = 0x50;
const CMD_ADC_READ: u8 = 0x00;
const CMD_PROM_READ: u8 = 0xA0;
/// Reset reload time (datasheet: 2.8 ms).
const RESET_DELAY_US: u32 = 2_800;

/// Oversampling ratio: resolution against conversion time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Oversampling {
    /// OSR 256.
    Osr256 = 0,
    /// OSR 512.
    Osr512 = 1,
    /// OSR 1024 (the flight default, as in Tau Labs' Sparky2 board files,
    /// `flight/targets/sparky2/`).
    Osr1024 = 2,
    /// OSR 2048.
    Osr2048 = 3,
    /// OSR 4096.
    Osr4096 = 4,
}

impl Oversampling {
    /// Command offset added to the convert commands.
    #[must_use]
    pub const fn command_offset(self) -> u8 {
        (self as u8) * 2
    }

    /// Maximum conversion time (datasheet table: 0.60/1.17/2.28/4.54/9.04 ms), rounded up.
    #[must_use]
    pub const fn conversion_time_us(self) -> u32 {
        match self {
            Self::Osr256 => 600,
            Self::Osr512 => 1_170,
            Self::Osr1024 => 2_280,
            Self::Osr2048 => 4_540,
            Self::Osr4096 => 9_040,
        }
    }
}

/// Driver errors; `E` is the I²C error, kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The I²C transfer failed (an absent device NACKs).
    Bus(E),
    /// The PROM's CRC-4 does not match: calibration data unusable.
    PromCrc {
        /// CRC stored in the PROM.
        stored: u8,
        /// CRC computed over it.
        computed: u8,
    },
    /// The ADC read 0: the conversion was not finished (or was interrupted by another
    /// command), datasheet "ADC read".
    ConversionNotReady,
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Bus(e) => write!(f, "I2C error: {e:?}"),
            Self::PromCrc { stored, computed } => {
                write!(f, "PROM CRC {stored:#x} != computed {computed:#x}")
            }
            Self::ConversionNotReady => f.write_str("ADC conversion not ready"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for Error<E> {}

/// A measurement: compensated pressure and temperature plus the altitude.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Measurement {
    /// Compensated reading.
    pub reading: Reading,
    /// ISA altitude above 1013.25 hPa (m).
    pub altitude_m: f32,
}

/// The driver.
#[derive(Debug)]
pub struct Ms5611<I2C> {
    i2c: I2C,
    address: u8,
    oversampling: Oversampling,
    prom: Prom,
}

impl<I2C: I2c> Ms5611<I2C> {
    /// Resets the chip, reads and checks its PROM.
    ///
    /// # Errors
    /// [`Error::Bus`] (no device answers), [`Error::PromCrc`].
    pub async fn new(
        i2c: I2C,
        address: u8,
        oversampling: Oversampling,
        delay: &mut impl DelayNs,
    ) -> Result<Self, Error<I2C::Error>> {
        let mut dev = Self {
            i2c,
            address,
            oversampling,
            prom: [0; 8],
        };
        dev.i2c
            .write(address, &[CMD_RESET])
            .await
            .map_err(Error::Bus)?;
        delay.delay_us(RESET_DELAY_US).await;
        let mut prom = [0u16; 8];
        for (i, word) in (0u8..).zip(prom.iter_mut()) {
            let mut buf = [0u8; 2];
            dev.i2c
                .write_read(address, &[CMD_PROM_READ + 2 * i], &mut buf)
                .await
                .map_err(Error::Bus)?;
            *word = u16::from_be_bytes(buf);
        }
        let (stored, computed) = (compensation::stored_crc(&prom), compensation::crc4(&prom));
        if stored != computed {
            return Err(Error::PromCrc { stored, computed });
        }
        dev.prom = prom;
        Ok(dev)
    }

    /// The calibration words.
    #[must_use]
    pub fn prom(&self) -> &Prom {
        &self.prom
    }

    /// One conversion of `command` (D1 or D2) at the configured oversampling.
    async fn convert(
        &mut self,
        command: u8,
        delay: &mut impl DelayNs,
    ) -> Result<u32, Error<I2C::Error>> {
        let cmd = command + self.oversampling.command_offset();
        self.i2c
            .write(self.address, &[cmd])
            .await
            .map_err(Error::Bus)?;
        delay.delay_us(self.oversampling.conversion_time_us()).await;
        let mut buf = [0u8; 3];
        self.i2c
            .write_read(self.address, &[CMD_ADC_READ], &mut buf)
            .await
            .map_err(Error::Bus)?;
        let [a, b, c] = buf;
        let raw = u32::from_be_bytes([0, a, b, c]);
        if raw == 0 {
            Err(Error::ConversionNotReady)
        } else {
            Ok(raw)
        }
    }

    /// Converts temperature then pressure and compensates them.
    ///
    /// # Errors
    /// [`Error::Bus`], [`Error::ConversionNotReady`].
    pub async fn measure(
        &mut self,
        delay: &mut impl DelayNs,
    ) -> Result<Measurement, Error<I2C::Error>> {
        let d2 = self.convert(CMD_CONVERT_D2, delay).await?;
        let d1 = self.convert(CMD_CONVERT_D1, delay).await?;
        let reading = compensation::compensate(&self.prom, d1, d2);
        #[allow(clippy::cast_precision_loss)] // Pa fits f32's 24-bit mantissa exactly
        let altitude_m = altitude_m(reading.pressure_pa as f32, 101_325.0);
        Ok(Measurement {
            reading,
            altitude_m,
        })
    }

    /// Gives the I²C bus back.
    pub fn release(self) -> I2C {
        self.i2c
    }
}
