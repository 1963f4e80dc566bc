//! The driver's error type: keeps the bus error, names what went wrong with the chip.

/// Everything the driver can fail with. `E` is the SPI bus error, kept as it came.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The SPI transfer itself failed.
    Bus(E),
    /// Register 0x00 did not read 0x08: no chip, an unpowered chip, or another part.
    NotAnSi4432 {
        /// What register 0x00 read.
        device_type: u8,
        /// What register 0x01 read.
        version: u8,
    },
    /// The chip did not report what was awaited (chip ready, packet sent, …) in time.
    Timeout,
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Bus(e) => write!(f, "SPI bus error: {e:?}"),
            Error::NotAnSi4432 {
                device_type,
                version,
            } => write!(
                f,
                "not an Si4432: device type 0x{device_type:02x}, version 0x{version:02x}"
            ),
            Error::Timeout => write!(f, "the radio did not answer in time"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for Error<E> {}
