//! SPI transcript tests (embedded-hal-mock) of reset and init: the whole configuration, the
//! SDN pulse, an unplugged chip (all 0x00 / all 0xFF), a chip that never gets ready, the
//! locked-module check and the run-time controls.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)] // test code

mod common;

use common::spi::*;
use embassy_futures::block_on;
use embedded_hal_mock::eh1::spi::Mock;
use radio_rfm22b::{Error, Rfm22b};

#[test]
fn init_writes_the_whole_configuration() {
    let radio = ready_radio(vec![], LowIrq, PATIENT);
    done(radio);
}

#[test]
fn sdn_pulse_precedes_the_reset() {
    use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as PinT};
    let sdn = PinMock::new(&[PinT::set(State::High), PinT::set(State::Low)]);
    let spi = Mock::new(&reset_transcript());
    let mut radio = Rfm22b::new(spi, LowIrq, sdn, PATIENT);
    block_on(radio.reset()).unwrap();
    let (mut spi, _, mut sdn, _) = radio.release();
    spi.done();
    sdn.done();
}

#[test]
fn unplugged_chip_is_not_an_si4432() {
    for floating in [0x00, 0xFF] {
        let spi = Mock::new(&r(0x00, &[floating, floating]));
        let mut radio = Rfm22b::new_without_sdn(spi, LowIrq, PATIENT);
        let err = block_on(radio.init(tau_config())).unwrap_err();
        assert_eq!(
            err,
            Error::NotAnSi4432 {
                device_type: floating,
                version: floating
            }
        );
        done(radio);
    }
}

#[test]
fn chip_that_never_gets_ready_times_out() {
    let mut t = [r(0x00, &[0x08, 0x04]), w(0x07, &[0x80])].concat();
    for _ in 0..50 {
        t.extend(r(0x03, &[0x00, 0x00]));
    }
    let spi = Mock::new(&t);
    let mut radio = Rfm22b::new_without_sdn(spi, LowIrq, PATIENT);
    assert_eq!(block_on(radio.init(tau_config())), Err(Error::Timeout));
    done(radio);
}

#[test]
fn locked_module_is_detected_and_reinitialised() {
    let t = [
        r(0x00, &[0x08, 0x06]),
        r(0x0C, &[0x00]),
        init_transcript(),
        // Second check: healthy.
        r(0x00, &[0x08, 0x06]),
        r(0x0C, &[0xD5]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    assert_eq!(block_on(radio.check_health()), Err(Error::ChipReset));
    assert_eq!(block_on(radio.check_health()), Ok(()));
    done(radio);
}

#[test]
fn channel_power_rssi_temperature_sleep() {
    let t = [
        w(0x79, &[17]),
        w(0x6D, &[0x0C]),
        r(0x26, &[45]),
        w(0x0F, &[0x80]),
        r(0x0F, &[0x00]),
        r(0x0F, &[0x80]),
        r(0x11, &[178]),
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    block_on(radio.set_channel(17)).unwrap();
    assert_eq!(radio.channel(), 17);
    block_on(radio.set_tx_power(radio_rfm22b::TxPower::try_from_dbm(11).unwrap())).unwrap();
    assert_eq!(block_on(radio.rssi_dbm()), Ok(-100));
    assert_eq!(block_on(radio.read_temperature_decidegrees_c()), Ok(250));
    block_on(radio.sleep()).unwrap();
    done(radio);
}

#[test]
fn headers_carrier_and_reconfiguration() {
    let t = [
        w(0x3A, &[0xDE, 0xAD, 0xFE, 0xED]),
        w(0x3F, &[0xDE, 0xAD, 0xFE, 0xEC]),
        // 868 MHz: hbsel 1, fb 19, fc 25600.
        w(0x75, &[0x73, 0x64, 0x00]),
        configure_transcript(),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    block_on(radio.set_tx_header([0xDE, 0xAD, 0xFE, 0xED])).unwrap();
    block_on(radio.set_check_header([0xDE, 0xAD, 0xFE, 0xEC])).unwrap();
    block_on(radio.set_carrier(radio_rfm22b::Carrier::new(868_000_000))).unwrap();
    assert_eq!(radio.config().unwrap().carrier.frequency_hz(), 868_000_000);
    // 48 preamble + 32 sync + 32 header + 8 length + 128 payload bits at 57.6 kbps.
    assert_eq!(radio.airtime_us(16), Some(4_306));
    // `apply` re-programs everything without a reset.
    block_on(radio.apply(tau_config())).unwrap();
    done(radio);
}
