//! The RF medium: path loss → RSSI, collisions and capture, random loss statistics, AFC
//! reading of a crystal offset.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

mod common;

use common::*;
use embedded_hal::delay::DelayNs;
use si4432_sim::{MediumConfig, Outcome, RadioConfig, RadioHandle, Simulation};

fn radio(sim: &Simulation, x_m: f64) -> RadioHandle {
    let mut r = sim.medium().add_radio(RadioConfig::at([x_m, 0.0, 0.0]));
    configure_57600(&mut r.spi, true);
    r
}

/// RSSI register latched at sync for a 16-byte packet sent over `distance_m`.
fn rssi_over(distance_m: f64) -> u8 {
    let sim = Simulation::new(11);
    let mut a = radio(&sim, 0.0);
    let mut b = radio(&sim, distance_m);
    start_rx(&mut b.spi);
    start_tx(&mut a.spi, 4, &[1, 2, 3, 4]);
    for _ in 0..1000 {
        a.delay.delay_us(10);
        if status(&mut b.spi).1 & 0x80 != 0 {
            return read(&mut b.spi, 0x26);
        }
    }
    panic!("no sync word detected");
}

#[test]
fn rssi_falls_20_db_per_decade_of_distance() {
    // +20 dBm, 430 MHz free space: P = 20 − 25.12 − 20·log10(d) dBm; raw = 2·(P + 122).
    assert_eq!(rssi_over(10.0), 194); // −25.12 dBm
    assert_eq!(rssi_over(100.0), 154); // −45.12 dBm
    assert_eq!(rssi_over(1000.0), 114); // −65.12 dBm
    assert_eq!(rssi_over(10_000.0), 74); // −85.12 dBm
}

/// A and B both send to C; B starts `b_delay_us` later. Returns the outcomes at C.
fn two_senders(
    config: MediumConfig,
    b_x_m: f64,
    b_delay_us: u32,
) -> (Option<Outcome>, Option<Outcome>) {
    let sim = Simulation::with_config(5, config);
    let mut a = radio(&sim, 0.0);
    let mut b = radio(&sim, b_x_m);
    let mut c = radio(&sim, 100.0);
    start_rx(&mut c.spi);
    start_tx(&mut a.spi, 20, &[0xA5; 20]);
    c.delay.delay_us(b_delay_us);
    start_tx(&mut b.spi, 20, &[0x5A; 20]);
    c.delay.delay_ms(10);
    let trace = sim.medium().trace();
    assert_eq!(trace.len(), 2);
    (trace[0].outcome_at(c.id), trace[1].outcome_at(c.id))
}

#[test]
fn equal_power_collision_loses_both() {
    // B at x = 200 m is as far from C (x = 100 m) as A (x = 0): equal power, SINR 0 dB.
    let (a, b) = two_senders(MediumConfig::default(), 200.0, 0);
    assert_eq!(b, Some(Outcome::Busy));
    assert!(
        matches!(
            a,
            Some(Outcome::CrcError { .. } | Outcome::HeaderMismatch | Outcome::SyncCorrupted)
        ),
        "{a:?}"
    );
}

#[test]
fn capture_effect_lets_a_much_stronger_late_frame_win() {
    // B at x = 90 m is 10 m from C: 20 dB stronger than A. It starts 300 µs into A's
    // 833 µs preamble, before C has detected A's sync word.
    let config = MediumConfig {
        capture_threshold_db: Some(6.0),
        ..MediumConfig::default()
    };
    let (a, b) = two_senders(config, 90.0, 300);
    assert_eq!(a, Some(Outcome::Captured));
    assert_eq!(b, Some(Outcome::Delivered { bit_errors: 0 }));
    // Without capture the receiver stays on A, which drowns 20 dB under B.
    let (a, b) = two_senders(MediumConfig::default(), 90.0, 300);
    assert_eq!(b, Some(Outcome::Busy));
    assert!(!matches!(a, Some(Outcome::Delivered { .. })), "{a:?}");
}

#[test]
fn random_loss_matches_its_probability() {
    let config = MediumConfig {
        packet_loss: 0.25,
        ..MediumConfig::default()
    };
    let sim = Simulation::with_config(99, config);
    let mut a = radio(&sim, 0.0);
    let mut b = radio(&sim, 100.0);
    let n = 400;
    for _ in 0..n {
        start_rx(&mut b.spi);
        start_tx(&mut a.spi, 8, &[3; 8]);
        a.delay.delay_ms(5); // 200 bits at 57.6 kbit/s = 3.5 ms + 0.2 ms settle
    }
    let (delivered, lost) = sim.medium().with_trace(|t| {
        let d = t
            .iter()
            .filter(|f| matches!(f.outcome_at(b.id), Some(Outcome::Delivered { .. })))
            .count();
        let l = t
            .iter()
            .filter(|f| f.outcome_at(b.id) == Some(Outcome::RandomLoss))
            .count();
        (d, l)
    });
    assert_eq!(delivered + lost, n);
    // Binomial(400, 0.25): mean 100, σ = 8.7; allow 4σ.
    assert!((lost as i64 - 100).abs() < 35, "lost {lost}");
}

#[test]
fn crystal_offset_shows_in_the_afc_reading() {
    let sim = Simulation::new(2);
    let config = RadioConfig {
        crystal_error_ppm: 20.0,
        ..RadioConfig::at([0.0, 0.0, 0.0])
    };
    let mut a = sim.medium().add_radio(config);
    configure_57600(&mut a.spi, true);
    let mut b = radio(&sim, 50.0);
    start_rx(&mut b.spi);
    start_tx(&mut a.spi, 4, &[9; 4]);
    b.delay.delay_ms(5);
    assert_eq!(
        status(&mut b.spi).0 & 0x02,
        0x02,
        "8.6 kHz is inside the 37.5 kHz AFC range"
    );
    // +20 ppm of 430 MHz = +8600 Hz = 55.04 steps of 156.25 Hz → 55 = 0b00_0011_0111:
    // 0x2B holds bits 9..2 (13), 0x2C[7:6] bits 1..0 (3).
    assert_eq!(read(&mut b.spi, 0x2B), 13);
    assert_eq!(read(&mut b.spi, 0x2C) >> 6, 3);
}

#[test]
fn near_sensitivity_bit_errors_are_caught_by_the_crc() {
    // 100 m (−45.12 dBm) plus 63.08 dB of attenuation: −108.2 dBm, 1 dB below the
    // −107.2 dBm sensitivity at 57.6 kbit/s, where BER ≈ 3.6·10⁻³: about half of the frames
    // lose at least one of their ~220 bits after the sync word.
    let sim = Simulation::new(17);
    let mut a = radio(&sim, 0.0);
    let mut b = radio(&sim, 100.0);
    sim.medium().set_attenuation(a.id, b.id, 63.08);
    let n = 300;
    for _ in 0..n {
        start_rx(&mut b.spi);
        start_tx(&mut a.spi, 16, &[0x3C; 16]);
        a.delay.delay_ms(6);
    }
    let outcomes: Vec<Outcome> = sim
        .medium()
        .with_trace(|t| t.iter().filter_map(|f| f.outcome_at(b.id)).collect());
    assert_eq!(outcomes.len(), n);
    let delivered = outcomes
        .iter()
        .filter(|o| matches!(o, Outcome::Delivered { .. }))
        .count();
    let crc_errors = outcomes
        .iter()
        .filter(|o| matches!(o, Outcome::CrcError { .. }))
        .count();
    // Every delivered frame is error-free: the CRC caught every flipped bit.
    assert!(
        outcomes
            .iter()
            .all(|o| !matches!(o, Outcome::Delivered { bit_errors } if *bit_errors > 0))
    );
    assert!(delivered > 90 && delivered < 210, "delivered {delivered}");
    assert!(crc_errors > 30, "crc errors {crc_errors}");
    let power = sim.medium().trace()[0].power_dbm[b.id.0];
    assert!((power + 108.2).abs() < 0.01, "{power}");
}

#[test]
fn rssi_threshold_interrupt_fires_for_strong_in_band_frames_only() {
    // Threshold 0x27 = 100 ≙ −72 dBm. Frames from 100 m arrive at −45 dBm (raw 154),
    // from 10 km at −85 dBm (raw 74).
    for (distance_m, channel, expected) in
        [(100.0, 0u8, 0x10u8), (10_000.0, 0, 0x00), (100.0, 5, 0x00)]
    {
        let sim = Simulation::new(6);
        let mut a = radio(&sim, 0.0);
        let mut b = radio(&sim, distance_m);
        write(&mut a.spi, 0x79, &[channel]);
        write(&mut b.spi, 0x27, &[100]);
        start_rx(&mut b.spi);
        write(&mut b.spi, 0x06, &[0x10]); // enrssi only
        b.delay.delay_us(300);
        assert_eq!(status(&mut b.spi).1 & 0x10, 0, "quiet channel: noise only");
        start_tx(&mut a.spi, 4, &[0; 4]);
        a.delay.delay_us(300);
        assert_eq!(
            status(&mut b.spi).1 & 0x10,
            expected,
            "{distance_m} m, channel {channel}"
        );
    }
}
