//! The driver's run-time error: keeps the bus error, names what went wrong with the chip.

use crate::ConfigError;

/// Everything a driver operation can fail with. `E` is the SPI bus error, kept as it came.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The SPI transfer itself failed.
    Bus(E),
    /// The nIRQ or SDN pin reported an error.
    Pin,
    /// Register 0x00 did not read 0x08: no chip, an unpowered chip, or another part.
    NotAnSi4432 {
        /// What register 0x00 read.
        device_type: u8,
        /// What register 0x01 read.
        version: u8,
    },
    /// The chip did not report what was awaited (chip ready, packet sent) in time.
    Timeout,
    /// The chip reset itself (power-on-reset flag, or its registers read back lost); the
    /// driver has re-initialised it and the operation in progress was abandoned.
    ChipReset,
    /// The FIFO over- or underflowed; both FIFOs were flushed.
    FifoError,
    /// A packet length the configuration cannot carry (0, over 255, or ≠ the fixed length).
    InvalidLength {
        /// The length given.
        len: usize,
    },
    /// The operation needs `init` first.
    NotInitialised,
    /// The configuration passed to `init` is invalid.
    Config(ConfigError),
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Bus(e) => write!(f, "SPI bus error: {e:?}"),
            Error::Pin => f.write_str("nIRQ/SDN pin error"),
            Error::NotAnSi4432 {
                device_type,
                version,
            } => write!(
                f,
                "not an Si4432: device type 0x{device_type:02x}, version 0x{version:02x}"
            ),
            Error::Timeout => f.write_str("the radio did not answer in time"),
            Error::ChipReset => f.write_str("the radio reset itself and was re-initialised"),
            Error::FifoError => f.write_str("radio FIFO under/overflow"),
            Error::InvalidLength { len } => write!(f, "invalid packet length {len}"),
            Error::NotInitialised => f.write_str("radio not initialised"),
            Error::Config(e) => write!(f, "invalid radio configuration: {e}"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for Error<E> {}

impl<E> From<ConfigError> for Error<E> {
    fn from(e: ConfigError) -> Self {
        Error::Config(e)
    }
}
