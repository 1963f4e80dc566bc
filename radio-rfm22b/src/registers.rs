//! Register addresses and fixed values from the Si4432 datasheet (rev 1.1, §9 "Register
//! table") that the driver needs.

/// 0x00 Device Type: reads 0x08 on every Si4430/31/32 ("EZRadioPRO transceiver").
pub const DEVICE_TYPE: u8 = 0x00;
/// 0x01 Device Version.
pub const DEVICE_VERSION: u8 = 0x01;
/// 0x02 Device Status.
pub const DEVICE_STATUS: u8 = 0x02;
/// 0x03 Interrupt/Status 1 (read clears).
pub const INTERRUPT_STATUS_1: u8 = 0x03;
/// 0x04 Interrupt/Status 2 (read clears).
pub const INTERRUPT_STATUS_2: u8 = 0x04;
/// 0x05 Interrupt Enable 1.
pub const INTERRUPT_ENABLE_1: u8 = 0x05;
/// 0x06 Interrupt Enable 2.
pub const INTERRUPT_ENABLE_2: u8 = 0x06;
/// 0x07 Operating & Function Control 1.
pub const OPERATING_MODE_1: u8 = 0x07;

/// Value of [`DEVICE_TYPE`] on a genuine part.
pub const DEVICE_TYPE_SI443X: u8 = 0x08;
/// 0x07 bit 7: software register reset.
pub const OPERATING_MODE_1_SWRESET: u8 = 0x80;
/// 0x04 bit 1: chip ready (crystal oscillator running).
pub const INTERRUPT_STATUS_2_CHIPRDY: u8 = 0x02;
