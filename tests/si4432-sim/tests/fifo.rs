//! FIFO behaviour through SPI: thresholds, overflow/underflow, clearing, no auto-increment
//! on 0x7F, and the RX side filling the FIFO from the air.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

mod common;

use common::*;
use embedded_hal::delay::DelayNs;
use si4432_sim::{RadioConfig, Simulation};

#[test]
fn tx_fifo_almost_full_overflow_and_clear() {
    let sim = Simulation::new(3);
    let mut r = sim.medium().add_radio(RadioConfig::default());
    status(&mut r.spi);
    write(&mut r.spi, 0x7C, &[10]);
    write(&mut r.spi, 0x7F, &[0xAA; 9]);
    assert_eq!(status(&mut r.spi).0 & 0x40, 0x00);
    write(&mut r.spi, 0x7F, &[0xAA]);
    assert_eq!(
        status(&mut r.spi).0 & 0x40,
        0x40,
        "itxffafull when the count reaches 10"
    );
    assert_eq!(r.chip.tx_fifo_len(), 10);
    // The burst stayed on 0x7F: nothing after it was written.
    assert_eq!(read(&mut r.spi, 0x00), 0x08);
    write(&mut r.spi, 0x7F, &[0x55; 54]);
    assert_eq!(r.chip.tx_fifo_len(), 64);
    assert_eq!(status(&mut r.spi).0 & 0x80, 0x00);
    write(&mut r.spi, 0x7F, &[0x55]);
    assert_eq!(status(&mut r.spi).0 & 0x80, 0x80, "ifferr on the 65th byte");
    assert_eq!(read(&mut r.spi, 0x02) & 0x80, 0x80, "ffovfl");
    // ffclrtx: write 1 then 0 (0x08).
    write(&mut r.spi, 0x08, &[0x01]);
    write(&mut r.spi, 0x08, &[0x00]);
    assert_eq!(r.chip.tx_fifo_len(), 0);
    assert_eq!(read(&mut r.spi, 0x02) & 0xC0, 0x00);
}

#[test]
fn reading_an_empty_rx_fifo_underflows() {
    let sim = Simulation::new(3);
    let mut r = sim.medium().add_radio(RadioConfig::default());
    status(&mut r.spi);
    assert_eq!(read(&mut r.spi, 0x02) & 0x20, 0x20, "rxffem");
    assert_eq!(read(&mut r.spi, 0x7F), 0x00);
    assert_eq!(status(&mut r.spi).0, 0x80);
    assert_eq!(read(&mut r.spi, 0x02) & 0x40, 0x40, "ffunfl");
}

/// Send `len` bytes from a fresh pair with the RX almost-full threshold at `rx_threshold`,
/// without draining the RX FIFO; returns the receiver's accumulated status 1 bits and how
/// many times irxffafull was seen.
fn receive_without_draining(len: usize, rx_threshold: u8) -> (u8, usize, usize) {
    let sim = Simulation::new(3);
    let medium = sim.medium();
    let mut a = medium.add_radio(RadioConfig::at([0.0, 0.0, 0.0]));
    let mut b = medium.add_radio(RadioConfig::at([20.0, 0.0, 0.0]));
    configure_57600(&mut a.spi, true);
    configure_57600(&mut b.spi, true);
    write(&mut b.spi, 0x7E, &[rx_threshold]);
    start_rx(&mut b.spi);
    let data: Vec<u8> = (0..len as u32).map(|i| i as u8).collect();
    start_tx(&mut a.spi, len as u8, &data[..len.min(64)]);
    let mut sent = len.min(64);
    let mut seen = 0;
    let mut full_events = 0;
    for _ in 0..2000 {
        a.delay.delay_us(20);
        let (s1, _) = status(&mut a.spi);
        if s1 & 0x20 != 0 && sent < len {
            let n = (len - sent).min(31);
            write(&mut a.spi, 0x7F, &data[sent..sent + n]);
            sent += n;
        }
        let (s1, _) = status(&mut b.spi);
        seen |= s1;
        full_events += usize::from(s1 & 0x10 != 0);
        if s1 & 0x03 != 0 {
            break;
        }
    }
    (seen, full_events, b.chip.rx_fifo_len())
}

#[test]
fn rx_almost_full_fires_once_at_the_threshold() {
    let (seen, full_events, held) = receive_without_draining(30, 10);
    assert_eq!(seen & 0x02, 0x02, "valid packet");
    assert_eq!(full_events, 1);
    assert_eq!(held, 30);
}

#[test]
fn rx_overflow_keeps_64_bytes_and_flags_a_fifo_error() {
    let (seen, _, held) = receive_without_draining(100, 32);
    assert_eq!(seen & 0x80, 0x80, "ifferr");
    assert_eq!(held, 64);
}

#[test]
fn tx_almost_empty_fires_when_the_count_falls_to_the_threshold() {
    let sim = Simulation::new(3);
    // Ideal bus: the loop below counts time in 10 µs delays only.
    let mut a = sim
        .medium()
        .add_radio(RadioConfig::default().with_instant_bus());
    configure_57600(&mut a.spi, true);
    write(&mut a.spi, 0x7D, &[20]);
    start_tx(&mut a.spi, 40, &[7; 40]);
    // Payload byte k leaves the FIFO when its first bit is due: 200 µs settle, then
    // (48 + 8·(9 + k)) bits at 57 601.9 bit/s. The count reaches 20 after 20 bytes (k = 19).
    let mut when = None;
    for step in 0..800u32 {
        a.delay.delay_us(10);
        if status(&mut a.spi).0 & 0x20 != 0 {
            when = Some(step * 10 + 10);
            break;
        }
    }
    let expected_us = 200.0 + (48.0 + 8.0 * (9.0 + 19.0)) * 1e6 / 57_601.93;
    let when = when.unwrap() as f64;
    assert!(
        when >= expected_us && when < expected_us + 10.0,
        "{when} vs {expected_us}"
    );
    assert_eq!(a.chip.tx_fifo_len(), 20);
}
