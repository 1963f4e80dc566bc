//! SPI transcript tests of reception: short and longer-than-FIFO packets with RSSI/AFC, CRC
//! error, too long for the buffer, timeout, power-on reset mid-RX, an all-0xFF bus, and a
//! dropped `receive` followed by a `transmit`.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)] // test code

mod common;

use common::spi::*;
use embassy_futures::block_on;
use embedded_hal_mock::eh1::spi::Mock;
use radio_rfm22b::{Error, Rfm22b, RxOutcome};

fn rx_start() -> Vec<T> {
    [
        w(0x08, &[0x02]),
        w(0x08, &[0x00]),
        w(0x05, &[0x93, 0x80]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x05]),
    ]
    .concat()
}

#[test]
fn receive_short_packet_with_rssi_and_afc() {
    let payload = [9, 8, 7, 6, 5];
    let t = [
        rx_start(),
        r(0x03, &[0x00, 0x80]),
        r(0x26, &[100]),
        r(0x2B, &[0x02, 0x40]),
        r(0x03, &[0x02, 0x00]),
        r(0x47, &[1, 2, 3, 4, 5]),
        r(0x7F, &payload),
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 64];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    let RxOutcome::Packet(p) = outcome else {
        panic!("{outcome:?}")
    };
    assert_eq!(p.len, 5);
    assert_eq!(buf[..5], payload);
    assert_eq!(p.header, [1, 2, 3, 4]);
    // raw 100 → 50 − 122 dBm; afc_corr = 0b00_0000_1001 = 9 steps of 156.25 Hz.
    assert_eq!(p.signal.rssi_dbm, -72);
    assert_eq!(p.signal.rssi_raw, 100);
    assert_eq!(p.signal.afc_offset_hz, 1_406);
    done(radio);
}

#[test]
fn receive_long_packet_drains_the_fifo() {
    let payload: Vec<u8> = (0..100).map(|i| 255 - i).collect();
    let head = [0xDE, 0xAD, 0xBE, 0xEF, 100];
    let t = [
        rx_start(),
        r(0x03, &[0x10, 0x80]),
        r(0x26, &[90]),
        r(0x2B, &[0xFF, 0xC0]),
        r(0x47, &head),
        r(0x7F, &payload[..32]),
        r(0x03, &[0x10, 0x00]),
        r(0x47, &head),
        r(0x7F, &payload[32..64]),
        r(0x03, &[0x10, 0x00]),
        r(0x47, &head),
        r(0x7F, &payload[64..96]),
        r(0x03, &[0x02, 0x00]),
        r(0x47, &head),
        r(0x7F, &payload[96..]),
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 255];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    let RxOutcome::Packet(p) = outcome else {
        panic!("{outcome:?}")
    };
    assert_eq!(p.len, 100);
    assert_eq!(buf[..100], payload[..]);
    assert_eq!(p.header, [0xDE, 0xAD, 0xBE, 0xEF]);
    assert_eq!(p.signal.rssi_dbm, -77);
    assert_eq!(p.signal.afc_offset_hz, -156);
    done(radio);
}

fn discard_tail() -> Vec<T> {
    [
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x08, &[0x02]),
        w(0x08, &[0x00]),
    ]
    .concat()
}

#[test]
fn receive_crc_error_is_an_outcome_and_flushes() {
    let t = [
        rx_start(),
        r(0x03, &[0x01, 0x80]),
        r(0x26, &[60]),
        r(0x2B, &[0x00, 0x00]),
        discard_tail(),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 64];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    let RxOutcome::CrcError(signal) = outcome else {
        panic!("{outcome:?}")
    };
    assert_eq!(signal.rssi_dbm, -92);
    done(radio);
}

#[test]
fn receive_too_long_for_the_buffer_is_discarded() {
    let t = [
        rx_start(),
        r(0x03, &[0x10, 0x00]),
        r(0x47, &[0, 0, 0, 0, 200]),
        r(0x26, &[80]),
        r(0x2B, &[0x00, 0x00]),
        discard_tail(),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 64];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    assert!(
        matches!(outcome, RxOutcome::TooLong { len: 200, .. }),
        "{outcome:?}"
    );
    done(radio);
}

#[test]
fn receive_timeout_is_an_outcome() {
    let t = [rx_start(), discard_tail(), r(0x00, &[0x08, 0x06])].concat();
    let mut radio = ready_radio(t, QuietIrq, EXPIRED);
    let mut buf = [0u8; 64];
    assert_eq!(
        block_on(radio.receive(&mut buf, 5_000)),
        Ok(RxOutcome::Timeout)
    );
    done(radio);
}

#[test]
fn power_on_reset_during_receive_reinitialises() {
    let t = [rx_start(), r(0x03, &[0x00, 0x01]), init_transcript()].concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 64];
    assert_eq!(
        block_on(radio.receive(&mut buf, 10_000_000)),
        Err(Error::ChipReset)
    );
    done(radio);
}

#[test]
fn all_ones_status_means_reset_then_not_an_si4432() {
    // A chip that drops off the bus mid-RX reads 0xFF everywhere: ipor looks set, the
    // re-init probe then fails cleanly.
    let t = [rx_start(), r(0x03, &[0xFF, 0xFF]), r(0x00, &[0xFF, 0xFF])].concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 64];
    assert_eq!(
        block_on(radio.receive(&mut buf, 10_000_000)),
        Err(Error::NotAnSi4432 {
            device_type: 0xFF,
            version: 0xFF
        })
    );
    done(radio);
}

#[test]
fn dropped_receive_is_stopped_by_the_next_operation() {
    // Start RX, drop the future after it armed the chip, then transmit.
    let t = [
        rx_start(),
        // The abort before the transmit.
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x08, &[0x01]),
        w(0x08, &[0x00]),
        w(0x3E, &[1]),
        w(0x7F, &[0x55]),
        w(0x05, &[0x84, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x09]),
        r(0x03, &[0x04, 0x00]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let line_low = std::rc::Rc::new(std::cell::Cell::new(false));
    let spi = Mock::new(&[init_transcript(), t].concat());
    let mut radio = Rfm22b::new_without_sdn(spi, SwitchIrq(line_low.clone()), PATIENT);
    block_on(radio.init(tau_config())).unwrap();
    {
        let mut buf = [0u8; 8];
        let mut rx = core::pin::pin!(radio.receive(&mut buf, 10_000_000));
        let mut cx = core::task::Context::from_waker(core::task::Waker::noop());
        assert!(rx.as_mut().poll(&mut cx).is_pending());
    }
    line_low.set(true);
    block_on(radio.transmit(&[0x55], 10_000_000)).unwrap();
    done(radio);
}

#[test]
fn packet_started_before_the_timeout_is_completed() {
    // The 5 ms timeout expires right after the sync interrupt; the packet still completes
    // within the extension (airtime of a 255-byte packet at 57.6 kbps ≈ 37 ms, which this
    // delay double never lets expire).
    let payload = [1, 2, 3];
    let t = [
        rx_start(),
        r(0x03, &[0x00, 0x80]),
        r(0x26, &[120]),
        r(0x2B, &[0x00, 0x00]),
        // Deadline: 0x31 pkrx says a packet is being received, so it gets the extension.
        r(0x31, &[0x10]),
        r(0x03, &[0x02, 0x00]),
        r(0x47, &[1, 2, 3, 4, 3]),
        r(0x7F, &payload),
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    // nIRQ low (sync) as the deadline expires: serviced once; the next wait is the deadline
    // (the pin is not consulted), then nIRQ low again for the valid packet.
    let irq = ScriptIrq([true, true].into());
    let mut radio = ready_radio(t, irq, TestDelay { limit_us: 10_000 });
    let mut buf = [0u8; 16];
    let outcome = block_on(radio.receive(&mut buf, 5_000)).unwrap();
    let RxOutcome::Packet(p) = outcome else {
        panic!("{outcome:?}")
    };
    assert_eq!(p.len, 3);
    assert_eq!(p.signal.rssi_dbm, -62);
    done(radio);
}

#[test]
fn a_refused_header_does_not_stretch_the_timeout() {
    // A sync word is seen (another link's packet), then the chip drops it on its header
    // check: 0x31 pkrx reads 0 at the deadline, so the receive times out on time.
    let t = [
        rx_start(),
        r(0x03, &[0x00, 0x80]),
        r(0x26, &[120]),
        r(0x2B, &[0x00, 0x00]),
        r(0x31, &[0x20]), // pksrch: back to searching
        discard_tail(),
        r(0x00, &[0x08, 0x06]),
    ]
    .concat();
    let irq = ScriptIrq([true, false].into());
    let mut radio = ready_radio(t, irq, TestDelay { limit_us: 10_000 });
    let mut buf = [0u8; 16];
    assert_eq!(
        block_on(radio.receive(&mut buf, 5_000)),
        Ok(RxOutcome::Timeout)
    );
    done(radio);
}

#[test]
fn unexpected_chip_ready_means_the_chip_reset() {
    let t = [rx_start(), r(0x03, &[0x00, 0x02]), init_transcript()].concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 16];
    assert_eq!(
        block_on(radio.receive(&mut buf, 10_000_000)),
        Err(Error::ChipReset)
    );
    done(radio);
}

#[test]
fn chip_ready_after_standby_is_expected() {
    let t = [
        // sleep(): READY, interrupts off, status, STANDBY.
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x00]),
        rx_start(),
        // The crystal restarts: chip-ready together with the packet.
        r(0x03, &[0x02, 0x02]),
        r(0x47, &[0, 0, 0, 0, 1]),
        r(0x7F, &[0x42]),
        r(0x26, &[140]),
        r(0x2B, &[0x00, 0x00]),
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    block_on(radio.sleep()).unwrap();
    let mut buf = [0u8; 16];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    assert!(matches!(outcome, RxOutcome::Packet(p) if p.len == 1 && p.signal.rssi_dbm == -52));
    assert_eq!(buf[0], 0x42);
    done(radio);
}

#[test]
fn fixed_length_packets_ignore_the_length_register() {
    let mut config = tau_config();
    config.packet = config
        .packet
        .with_length(radio_rfm22b::PacketLength::Fixed(4));
    let mut t = init_transcript();
    // 0x33 gets fixpklen (0x08) and 0x3E the length.
    let pos = t
        .iter()
        .position(|x| *x == embedded_hal_mock::eh1::spi::Transaction::write(0x32 | 0x80))
        .unwrap();
    t[pos + 1] = embedded_hal_mock::eh1::spi::Transaction::write_vec(vec![0xFF, 0x4E, 0x0C, 0x30]);
    let pos = t
        .iter()
        .position(|x| *x == embedded_hal_mock::eh1::spi::Transaction::write(0x36 | 0x80))
        .unwrap();
    t[pos + 1] = embedded_hal_mock::eh1::spi::Transaction::write_vec(vec![
        0x2D, 0xD4, 0x4B, 0x59, 1, 2, 3, 4, 4, 1, 2, 3, 4, 0xFF, 0xFF, 0xFF, 0xFF,
    ]);
    t.extend(
        [
            rx_start(),
            r(0x03, &[0x02, 0x80]),
            r(0x26, &[100]),
            r(0x2B, &[0x00, 0x00]),
            // 0x4B reads garbage in fixed mode; the configured 4 bytes are read.
            r(0x47, &[1, 2, 3, 4, 0xEE]),
            r(0x7F, &[10, 20, 30, 40]),
            w(0x07, &[0x01]),
            w(0x05, &[0x00, 0x00]),
        ]
        .concat(),
    );
    let spi = Mock::new(&t);
    let mut radio = Rfm22b::new_without_sdn(spi, LowIrq, PATIENT);
    block_on(radio.init(config)).unwrap();
    let mut buf = [0u8; 8];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    assert!(matches!(outcome, RxOutcome::Packet(p) if p.len == 4));
    assert_eq!(buf[..4], [10, 20, 30, 40]);
    assert_eq!(
        block_on(radio.transmit(&[1, 2, 3], 1_000)),
        Err(Error::InvalidLength { len: 3 })
    );
    done(radio);
}

#[test]
fn each_sync_latches_its_own_signal() {
    // A first sync whose packet the header check drops (no further interrupt), then a
    // second packet: its own RSSI is reported.
    let t = [
        rx_start(),
        r(0x03, &[0x00, 0x80]),
        r(0x26, &[60]),
        r(0x2B, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x80]),
        r(0x26, &[160]),
        r(0x2B, &[0x00, 0x00]),
        r(0x03, &[0x02, 0x00]),
        r(0x47, &[1, 2, 3, 4, 2]),
        r(0x7F, &[7, 7]),
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 16];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    assert!(
        matches!(outcome, RxOutcome::Packet(p) if p.signal.rssi_dbm == -42),
        "{outcome:?}"
    );
    done(radio);
}
