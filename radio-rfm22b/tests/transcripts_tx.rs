//! SPI transcript tests of transmission: short and longer-than-FIFO packets, length checks,
//! and a timeout on a chip that has vanished from the bus.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)] // test code

mod common;

use common::spi::*;
use embassy_futures::block_on;
use radio_rfm22b::Error;

#[test]
fn transmit_short_packet() {
    let t = [
        w(0x08, &[0x01]),
        w(0x08, &[0x00]),
        w(0x3E, &[3]),
        w(0x7F, &[0x00, 0x11, 0x22]),
        w(0x05, &[0x84, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x09]),
        r(0x03, &[0x04, 0x00]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    block_on(radio.transmit(&[0x00, 0x11, 0x22], 10_000_000)).unwrap();
    done(radio);
}

#[test]
fn transmit_long_packet_refills_the_fifo() {
    let data: Vec<u8> = (0..100).collect();
    let t = [
        w(0x08, &[0x01]),
        w(0x08, &[0x00]),
        w(0x3E, &[100]),
        w(0x7F, &data[..64]),
        w(0x05, &[0xA4, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x09]),
        r(0x03, &[0x20, 0x00]),
        w(0x7F, &data[64..95]),
        r(0x03, &[0x20, 0x00]),
        w(0x7F, &data[95..]),
        w(0x05, &[0x84]),
        r(0x03, &[0x04, 0x00]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    block_on(radio.transmit(&data, 10_000_000)).unwrap();
    done(radio);
}

#[test]
fn transmit_rejects_bad_lengths_without_bus_traffic() {
    let mut radio = ready_radio(vec![], LowIrq, PATIENT);
    assert_eq!(
        block_on(radio.transmit(&[], 1_000)),
        Err(Error::InvalidLength { len: 0 })
    );
    assert_eq!(
        block_on(radio.transmit(&[0; 256], 1_000)),
        Err(Error::InvalidLength { len: 256 })
    );
    done(radio);
}

#[test]
fn transmit_timeout_on_a_vanished_chip_reports_it() {
    let t = [
        w(0x08, &[0x01]),
        w(0x08, &[0x00]),
        w(0x3E, &[1]),
        w(0x7F, &[0xAA]),
        w(0x05, &[0x84, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x09]),
        // Deadline: idle, interrupts off, clear status, flush TX, probe.
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x08, &[0x01]),
        w(0x08, &[0x00]),
        r(0x00, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, QuietIrq, EXPIRED);
    assert_eq!(
        block_on(radio.transmit(&[0xAA], 1_000)),
        Err(Error::NotAnSi4432 {
            device_type: 0,
            version: 0
        })
    );
    done(radio);
}
