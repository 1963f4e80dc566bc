//! Transcript tests: the exact SPI traffic of bring-up and reads, against register values
//! written out independently of the driver's constants.

use embassy_futures::block_on;
use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::spi::{Mock, Transaction as T};

use super::{Config, Error, Mpu9250};

fn write(reg: u8, value: u8) -> Vec<T<u8>> {
    vec![
        T::transaction_start(),
        T::write_vec(vec![reg, value]),
        T::transaction_end(),
    ]
}

fn read(reg: u8, response: Vec<u8>) -> Vec<T<u8>> {
    vec![
        T::transaction_start(),
        T::write_vec(vec![reg | 0x80]),
        T::read_vec(response),
        T::transaction_end(),
    ]
}

/// Bring-up up to the gyro-range read-back, for ±2000 °/s, ±8 g, 184 Hz, 500 Hz.
fn core_bring_up(mag: bool) -> Vec<T<u8>> {
    let mut t = Vec::new();
    t.extend(write(0x6B, 0x80)); // H_RESET
    t.extend(read(0x75, vec![0x71])); // WHO_AM_I
    t.extend(write(0x6B, 0x01)); // PLL clock
    t.extend(write(0x6C, 0x00));
    t.extend(write(0x6A, if mag { 0x30 } else { 0x10 })); // I2C_IF_DIS (+ I2C_MST_EN)
    t.extend(write(0x1A, 0x01)); // DLPF 184 Hz
    t.extend(write(0x19, 0x01)); // 1 kHz / 2 = 500 Hz
    t.extend(write(0x1B, 0x18)); // ±2000 °/s
    t.extend(write(0x1C, 0x10)); // ±8 g
    t.extend(write(0x1D, 0x01)); // accel DLPF 184 Hz
    t.extend(read(0x1B, vec![0x18]));
    t
}

fn ak_write(reg: u8, value: u8) -> Vec<T<u8>> {
    let mut t = write(0x25, 0x0C);
    t.extend(write(0x26, reg));
    t.extend(write(0x63, value));
    t.extend(write(0x27, 0x81));
    t
}

fn ak_read(reg: u8, response: Vec<u8>) -> Vec<T<u8>> {
    let mut t = write(0x25, 0x8C);
    t.extend(write(0x26, reg));
    t.extend(write(0x27, 0x80 | response.len() as u8));
    t.extend(read(0x49, response));
    t
}

fn mag_bring_up(wia: u8, asa: [u8; 3]) -> Vec<T<u8>> {
    let mut t = write(0x24, 0x0D); // I²C master 400 kHz
    t.extend(ak_write(0x0B, 0x01)); // SRST
    t.extend(ak_read(0x00, vec![wia]));
    if wia != 0x48 {
        return t;
    }
    t.extend(ak_write(0x0A, 0x00));
    t.extend(ak_write(0x0A, 0x0F));
    t.extend(ak_read(0x10, asa.to_vec()));
    t.extend(ak_write(0x0A, 0x00));
    t.extend(ak_write(0x0A, 0x16));
    t.extend(write(0x25, 0x8C));
    t.extend(write(0x26, 0x02));
    t.extend(write(0x27, 0x88));
    t
}

fn interrupts() -> Vec<T<u8>> {
    let mut t = write(0x37, 0x30);
    t.extend(write(0x38, 0x01));
    t
}

#[test]
fn bring_up_with_magnetometer_and_burst_read() {
    // GIVEN a responsive MPU-9250 and AK8963 with ASA = [128, 192, 64]
    let mut t = core_bring_up(true);
    t.extend(mag_bring_up(0x48, [128, 192, 64]));
    t.extend(interrupts());
    // AND a burst: accel x = +4096 LSB (1 g at ±8 g), temp 0, gyro z = −1640 LSB
    // (≈ −100 °/s at ±2000), mag ST1 ready, x = 100, y = −200, z = 300 LSB, ST2 ok
    let mut burst = vec![0x10, 0x00, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
    burst.extend((-1640i16).to_be_bytes());
    burst.push(0x01);
    burst.extend(100i16.to_le_bytes());
    burst.extend((-200i16).to_le_bytes());
    burst.extend(300i16.to_le_bytes());
    burst.push(0x10);
    t.extend(read(0x3B, burst));
    let mut spi = Mock::new(&t);
    // WHEN the driver starts and reads a sample
    let mut dev = block_on(Mpu9250::new(
        spi.clone(),
        Config::default(),
        &mut NoopDelay::new(),
    ))
    .unwrap();
    let s = block_on(dev.read()).unwrap();
    // THEN the values are scaled to SI units
    assert!(
        (s.accel_mps2[0] - 9.80665).abs() < 1e-4,
        "{:?}",
        s.accel_mps2
    );
    let expected_gyro = (-1640.0_f32 * 2000.0 / 32768.0).to_radians();
    assert!(
        (s.gyro_radps[2] - expected_gyro).abs() < 1e-5,
        "{:?}",
        s.gyro_radps
    );
    assert!((s.temperature_c - 21.0).abs() < 1e-6);
    // AND the magnetometer is sensitivity-adjusted (ASA 128 → ×1, 192 → ×1.25, 64 → ×0.75)
    // and rotated into the MPU axes (x = y_ak, y = x_ak, z = −z_ak)
    let m = s.mag_ut.unwrap();
    assert!((m[0] - (-200.0 * 0.15 * 1.25)).abs() < 1e-4, "{m:?}");
    assert!((m[1] - 100.0 * 0.15).abs() < 1e-4, "{m:?}");
    assert!((m[2] - (-300.0 * 0.15 * 0.75)).abs() < 1e-4, "{m:?}");
    spi.done();
}

#[test]
fn a_warm_start_is_the_bring_up_without_the_reset() {
    // GIVEN a chip that kept its power (and its old configuration) across the host's reset
    let mut t = core_bring_up(true);
    // The bring-up without its first transaction, the H_RESET write (0x6B ← 0x80).
    t.drain(..write(0x6B, 0x80).len());
    t.extend(mag_bring_up(0x48, [128, 128, 128]));
    t.extend(interrupts());
    let mut spi = Mock::new(&t);
    // WHEN the driver starts warm: every register written again, no H_RESET
    let dev = block_on(Mpu9250::new_warm(
        spi.clone(),
        Config::default(),
        &mut NoopDelay::new(),
    ));
    // THEN it is configured, the magnetometer's scale read
    assert!(dev.is_ok());
    spi.done();
}

#[test]
fn bring_up_without_magnetometer_reads_14_bytes() {
    let mut t = core_bring_up(false);
    t.extend(interrupts());
    t.extend(read(0x3B, vec![0; 14]));
    let mut spi = Mock::new(&t);
    let config = Config {
        magnetometer: false,
        ..Config::default()
    };
    let mut dev = block_on(Mpu9250::new(spi.clone(), config, &mut NoopDelay::new())).unwrap();
    let s = block_on(dev.read()).unwrap();
    assert_eq!(s.mag_ut, None);
    assert_eq!(s.accel_mps2, [0.0; 3]);
    spi.done();
}

#[test]
fn absent_chip_is_a_typed_error_after_bounded_polling() {
    // GIVEN nothing on the bus (MISO floats high): WHO_AM_I reads 0xFF five times
    let mut t = write(0x6B, 0x80);
    for _ in 0..5 {
        t.extend(read(0x75, vec![0xFF]));
    }
    let mut spi = Mock::new(&t);
    // WHEN the driver starts THEN it gives up with NotFound instead of hanging
    let r = block_on(Mpu9250::new(
        spi.clone(),
        Config::default(),
        &mut NoopDelay::new(),
    ));
    assert!(matches!(r, Err(Error::NotFound { who_am_i: 0xFF })));
    spi.done();
}

#[test]
fn missing_magnetometer_is_reported() {
    let mut t = core_bring_up(true);
    t.extend(mag_bring_up(0x00, [0; 3]));
    let mut spi = Mock::new(&t);
    let r = block_on(Mpu9250::new(
        spi.clone(),
        Config::default(),
        &mut NoopDelay::new(),
    ));
    assert!(matches!(r, Err(Error::MagnetometerNotFound { wia: 0x00 })));
    spi.done();
}

#[test]
fn register_that_does_not_stick_is_reported() {
    let mut t = core_bring_up(false);
    let n = t.len();
    t.truncate(n - 4);
    t.extend(read(0x1B, vec![0x00]));
    let mut spi = Mock::new(&t);
    let config = Config {
        magnetometer: false,
        ..Config::default()
    };
    let r = block_on(Mpu9250::new(spi.clone(), config, &mut NoopDelay::new()));
    assert!(matches!(
        r,
        Err(Error::ConfigMismatch {
            register: 0x1B,
            read: 0x00
        })
    ));
    spi.done();
}

#[test]
fn overflowed_magnetometer_sample_is_dropped() {
    let mut t = core_bring_up(true);
    t.extend(mag_bring_up(0x48, [128; 3]));
    t.extend(interrupts());
    let mut burst = vec![0; 14];
    burst.extend([0x01, 1, 0, 1, 0, 1, 0, 0x18]); // ST2.HOFL set
    t.extend(read(0x3B, burst));
    let mut spi = Mock::new(&t);
    let mut dev = block_on(Mpu9250::new(
        spi.clone(),
        Config::default(),
        &mut NoopDelay::new(),
    ))
    .unwrap();
    assert_eq!(block_on(dev.read()).unwrap().mag_ut, None);
    spi.done();
}

#[test]
fn sample_rate_1khz_and_other_ranges() {
    use super::{AccelRange, Dlpf, GyroRange, SampleRate};
    assert_eq!(SampleRate::Hz1000.divider(), 0);
    assert_eq!(SampleRate::Hz500.frequency_hz(), 500);
    assert!((GyroRange::Dps250.radps_per_lsb() - 250f32.to_radians() / 32768.0).abs() < 1e-9);
    assert!((AccelRange::G2.mps2_per_lsb() * 16384.0 - 9.80665).abs() < 1e-5);
    assert_eq!(Dlpf::Hz41 as u8, 3);
}
