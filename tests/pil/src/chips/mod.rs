//! The chips on the boards, register by register, written from their datasheets (not from
//! the project's drivers, so a driver bug shows against them): each one is what the MCU
//! model reaches through a board's pins, SPI, I²C or UART, on the co-simulation's virtual
//! time (ns since power-on).
//!
//! - [`mpu9250`]: the MPU-9250 on SPI, its sample clock and data-ready INT, with the
//!   [`ak8963`] magnetometer behind its I²C master;
//! - [`ms5611`]: the MS5611 barometer on I²C, with the stuck-bus fault;
//! - [`rfm22b`]: an RFM22B module on SPI, a `si4432-sim` chip on the shared RF medium;
//! - [`m25p16`]: the M25P16 serial flash on SPI (identification, silence when deselected);
//! - [`ublox`]: a u-blox receiver on a UART (UBX configuration, NAV-PVT from the truth);
//! - [`hm10`]: the HM-10 BLE bridge on a UART (HMSoft AT commands, a phone that connects);
//! - [`handset`]: the EdgeTX handset in the JR bay (PPM on a pin, CRSF on the half-duplex
//!   line behind the module's XOR and buffer);
//! - [`uart`]: a UART line between two ends at their own baud rates (a receiver at the wrong
//!   rate reads what its sampling makes of the waveform);
//! - [`motors`]: motor output pins read back as pulse widths and duty, into commands.

pub mod ak8963;
pub mod handset;
pub mod hm10;
pub mod m25p16;
pub mod motors;
pub mod mpu9250;
pub mod ms5611;
pub mod rfm22b;
pub mod uart;
pub mod ublox;

/// Standard gravity, m/s² (the MPU-9250's g).
pub const G_MPS2: f64 = 9.806_65;

/// A pulse or level on an output pin of a chip, as the board sees it: (time ns, level).
pub type Edge = (u64, bool);
