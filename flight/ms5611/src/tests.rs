//! I²C transcript tests of the MS5611 driver, with the datasheet's example calibration.

use embassy_futures::block_on;
use embedded_hal::i2c::ErrorKind;
use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::i2c::{Mock, Transaction as T};

use super::compensation::crc4;
use super::{Error, Ms5611, Oversampling};

const ADDR: u8 = 0x77;

fn prom_with_crc() -> [u16; 8] {
    let mut prom = [0x0042, 40127, 36924, 23317, 23282, 33464, 28312, 0x1200];
    prom[7] |= u16::from(crc4(&prom));
    prom
}

fn bring_up(prom: [u16; 8]) -> Vec<T> {
    let mut t = vec![T::write(ADDR, vec![0x1E])];
    for (i, w) in prom.iter().enumerate() {
        t.push(T::write_read(
            ADDR,
            vec![0xA0 + 2 * i as u8],
            w.to_be_bytes().to_vec(),
        ));
    }
    t
}

fn adc(value: u32) -> Vec<u8> {
    value.to_be_bytes()[1..].to_vec()
}

#[test]
fn reset_prom_and_measure_at_osr_1024() {
    // GIVEN the datasheet example device
    let mut t = bring_up(prom_with_crc());
    // WHEN measuring at OSR 1024: D2 (0x54) then D1 (0x44), each followed by an ADC read
    t.push(T::write(ADDR, vec![0x54]));
    t.push(T::write_read(ADDR, vec![0x00], adc(8_569_150)));
    t.push(T::write(ADDR, vec![0x44]));
    t.push(T::write_read(ADDR, vec![0x00], adc(9_085_466)));
    let mut i2c = Mock::new(&t);
    let mut baro = block_on(Ms5611::new(
        i2c.clone(),
        ADDR,
        Oversampling::Osr1024,
        &mut NoopDelay::new(),
    ))
    .unwrap();
    let m = block_on(baro.measure(&mut NoopDelay::new())).unwrap();
    // THEN the datasheet's 20.07 °C and 1000.09 mbar come out, and the ISA altitude of
    // 100 009 Pa is 110.13 m (44 330.77·(1 − (100 009/101 325)^0.190263), in f64)
    assert_eq!(m.reading.temperature_centi_c, 2007);
    assert_eq!(m.reading.pressure_pa, 100_009);
    let expected = 44_330.77 * (1.0 - (100_009.0_f64 / 101_325.0).powf(0.190_263));
    assert!(
        (f64::from(m.altitude_m) - expected).abs() < 0.05,
        "{} vs {expected}",
        m.altitude_m
    );
    i2c.done();
}

#[test]
fn osr_4096_uses_its_commands() {
    let mut t = bring_up(prom_with_crc());
    t.push(T::write(ADDR, vec![0x58]));
    t.push(T::write_read(ADDR, vec![0x00], adc(8_569_150)));
    t.push(T::write(ADDR, vec![0x48]));
    t.push(T::write_read(ADDR, vec![0x00], adc(9_085_466)));
    let mut i2c = Mock::new(&t);
    let mut baro = block_on(Ms5611::new(
        i2c.clone(),
        ADDR,
        Oversampling::Osr4096,
        &mut NoopDelay::new(),
    ))
    .unwrap();
    assert!(block_on(baro.measure(&mut NoopDelay::new())).is_ok());
    assert_eq!(Oversampling::Osr4096.conversion_time_us(), 9_040);
    i2c.done();
}

#[test]
fn corrupted_prom_is_rejected() {
    let mut prom = prom_with_crc();
    prom[2] ^= 0x0004;
    let mut i2c = Mock::new(&bring_up(prom));
    let r = block_on(Ms5611::new(
        i2c.clone(),
        ADDR,
        Oversampling::Osr1024,
        &mut NoopDelay::new(),
    ));
    assert!(matches!(r, Err(Error::PromCrc { .. })));
    i2c.done();
}

#[test]
fn absent_device_is_a_bus_error() {
    // GIVEN nobody acknowledges the reset
    let t = [
        T::write(ADDR, vec![0x1E]).with_error(ErrorKind::NoAcknowledge(
            embedded_hal::i2c::NoAcknowledgeSource::Address,
        )),
    ];
    let mut i2c = Mock::new(&t);
    let r = block_on(Ms5611::new(
        i2c.clone(),
        ADDR,
        Oversampling::Osr1024,
        &mut NoopDelay::new(),
    ));
    assert!(matches!(r, Err(Error::Bus(ErrorKind::NoAcknowledge(_)))));
    i2c.done();
}

#[test]
fn unfinished_conversion_is_reported() {
    let mut t = bring_up(prom_with_crc());
    t.push(T::write(ADDR, vec![0x54]));
    t.push(T::write_read(ADDR, vec![0x00], adc(0)));
    let mut i2c = Mock::new(&t);
    let mut baro = block_on(Ms5611::new(
        i2c.clone(),
        ADDR,
        Oversampling::Osr1024,
        &mut NoopDelay::new(),
    ))
    .unwrap();
    assert!(matches!(
        block_on(baro.measure(&mut NoopDelay::new())),
        Err(Error::ConversionNotReady)
    ));
    i2c.done();
}
