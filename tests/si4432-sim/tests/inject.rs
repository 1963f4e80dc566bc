//! Frames injected from an ideal transmitter (no second chip): the receiver's own format.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

mod common;

use common::*;
use embedded_hal::delay::DelayNs;
use si4432_sim::{Outcome, RadioConfig, RadioId, Simulation};

#[test]
fn injected_packet_reaches_a_receiver_in_its_own_format() {
    let sim = Simulation::new(4);
    let medium = sim.medium();
    let mut r = medium.add_radio(RadioConfig::default());
    configure_57600(&mut r.spi, true);
    start_rx(&mut r.spi);
    r.delay.delay_us(200);
    let id = medium.inject_packet(r.id, b"hello", -70.0).unwrap();
    r.delay.delay_ms(5);
    let (s1, s2) = status(&mut r.spi);
    assert_eq!(s1 & 0x02, 0x02);
    assert_eq!(s2 & 0xC0, 0xC0, "valid preamble and sync word on the way");
    assert_eq!(read(&mut r.spi, 0x4B), 5);
    assert_eq!(read_n(&mut r.spi, 0x7F, 5), b"hello".to_vec());
    // −70 dBm: 2·(−70 + 122) = 104.
    assert_eq!(read(&mut r.spi, 0x26), 104);
    let frame = &medium.trace()[id as usize];
    assert_eq!(frame.radio, RadioId::INJECTED);
    assert_eq!(
        frame.outcome_at(r.id),
        Some(Outcome::Delivered { bit_errors: 0 })
    );
}

#[test]
fn injected_packet_below_sensitivity_or_to_an_idle_chip_is_not_heard() {
    let sim = Simulation::new(4);
    let medium = sim.medium();
    let mut r = medium.add_radio(RadioConfig::default());
    configure_57600(&mut r.spi, true);
    let id = medium.inject_packet(r.id, b"x", -60.0).unwrap();
    assert_eq!(
        medium.trace()[id as usize].outcome_at(r.id),
        Some(Outcome::NotListening)
    );
    // Let it pass: a receiver that settles within its preamble would still catch it.
    r.delay.delay_ms(5);
    start_rx(&mut r.spi);
    r.delay.delay_us(200);
    let id = medium.inject_packet(r.id, b"x", -120.0).unwrap();
    r.delay.delay_ms(5);
    assert_eq!(
        medium.trace()[id as usize].outcome_at(r.id),
        Some(Outcome::TooWeak)
    );
    assert_eq!(status(&mut r.spi).0 & 0x03, 0);
}

#[test]
fn reset_register_defaults_also_receive_injected_packets() {
    // Reset values (915 MHz, 40 kbit/s, 20 kHz, CRC-16, header 3/2 checked against 0x0000)
    // except 0x71: the reset modulation is an unmodulated carrier, so pick FSK from the FIFO.
    let sim = Simulation::new(4);
    let medium = sim.medium();
    let mut r = medium.add_radio(RadioConfig::default());
    status(&mut r.spi);
    write(&mut r.spi, 0x71, &[0x22]);
    write(&mut r.spi, 0x05, &[0x02]);
    write(&mut r.spi, 0x07, &[0x05]);
    r.delay.delay_us(200);
    medium.inject_packet(r.id, &[1, 2, 3], -50.0).unwrap();
    r.delay.delay_ms(5);
    assert_eq!(status(&mut r.spi).0, 0x02);
    assert_eq!(read_n(&mut r.spi, 0x7F, 3), vec![1, 2, 3]);
    assert_eq!(read_n(&mut r.spi, 0x47, 2), vec![0, 0]);
}
