//! Sensor drivers over embedded-hal-async: the MPU9250 IMU (SPI) with its AK8963
//! magnetometer behind the MPU's I²C master, and the MS5611 barometer (I²C). Delays are
//! injected (`DelayNs`), so every wait is bounded and the drivers run in host tests against
//! `embedded-hal-mock` transcripts. The u-blox GPS ([`ubx`]) is sans-IO: bytes in, fixes out.

pub mod mpu9250;
pub mod ms5611;
pub mod ubx;
