//! Two virtual chips through the medium, driven by raw register sequences (blocking SPI and
//! a busy-polling loop on nIRQ): short and long packets, wrong channel or rate, CRC errors,
//! RSSI and airtime numbers.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

mod common;

use common::*;
use core::time::Duration;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::InputPin;
use si4432_sim::modem::Mismatch;
use si4432_sim::{ChipState, Interference, Outcome, RadioConfig, RadioHandle, RadioId, Simulation};

fn pair(distance_m: f64) -> (Simulation, RadioHandle, RadioHandle) {
    let sim = Simulation::new(7);
    let medium = sim.medium();
    let mut a = medium.add_radio(RadioConfig::at([0.0, 0.0, 0.0]));
    let mut b = medium.add_radio(RadioConfig::at([distance_m, 0.0, 0.0]));
    configure_57600(&mut a.spi, true);
    configure_57600(&mut b.spi, true);
    (sim, a, b)
}

fn payload(n: usize) -> Vec<u8> {
    (0..n).map(|i| (i * 7 + 3) as u8).collect()
}

/// What the polling loop saw at the receiver.
#[derive(Debug, Default)]
struct Received {
    data: Vec<u8>,
    valid: bool,
    crc_error: bool,
    fifo_error_tx: bool,
    sent: bool,
    rssi_at_sync: Option<u8>,
    header: Vec<u8>,
}

/// Send `data` from `a` to `b`, refilling at TX almost-empty and draining at RX almost-full,
/// polling nIRQ every 20 µs for at most `limit`. `refill` = false leaves the TX FIFO dry.
fn exchange(
    a: &mut RadioHandle,
    b: &mut RadioHandle,
    data: &[u8],
    refill: bool,
    limit: Duration,
) -> Received {
    let mut got = Received::default();
    start_rx(&mut b.spi);
    let first = data.len().min(64);
    start_tx(&mut a.spi, data.len() as u8, &data[..first]);
    let mut next = first;
    let mut waited = Duration::ZERO;
    while waited < limit && !(got.sent && (got.valid || got.crc_error)) {
        a.delay.delay_us(20);
        waited += Duration::from_micros(20);
        if a.nirq.is_low().unwrap() {
            let (s1, _) = status(&mut a.spi);
            got.fifo_error_tx |= s1 & 0x80 != 0;
            if s1 & 0x20 != 0 && refill && next < data.len() {
                let n = (data.len() - next).min(31);
                write(&mut a.spi, 0x7F, &data[next..next + n]);
                next += n;
            }
            got.sent |= s1 & 0x04 != 0;
        }
        if b.nirq.is_low().unwrap() {
            let (s1, s2) = status(&mut b.spi);
            if s2 & 0x80 != 0 {
                got.rssi_at_sync = Some(read(&mut b.spi, 0x26));
            }
            if s1 & 0x02 != 0 {
                let length = read(&mut b.spi, 0x4B) as usize;
                let rest = length - got.data.len();
                got.data.extend(read_n(&mut b.spi, 0x7F, rest));
                got.header = read_n(&mut b.spi, 0x47, 4);
                got.valid = true;
            } else if s1 & 0x10 != 0 {
                got.data.extend(read_n(&mut b.spi, 0x7F, 32));
            }
            got.crc_error |= s1 & 0x01 != 0;
        }
    }
    got
}

#[test]
fn short_packet_is_delivered_with_header_length_and_rssi() {
    let (sim, mut a, mut b) = pair(100.0);
    let data = payload(16);
    let got = exchange(&mut a, &mut b, &data, true, Duration::from_millis(20));
    assert!(got.sent && got.valid && !got.crc_error, "{got:?}");
    assert_eq!(got.data, data);
    assert_eq!(got.header, vec![0x12, 0x34, 0x56, 0x78]);
    // Free space at 430 MHz over 100 m: 20·log10(4π·100/λ) = 65.11 dB, so +20 dBm arrives
    // at −45.11 dBm; RSSI = 2·(dBm + 122) = 153.8 → 154 (rssi_off 0).
    assert_eq!(got.rssi_at_sync, Some(154));
    let power = sim.medium().received_power_dbm(a.id, b.id, 430e6, 20.0);
    assert!((power + 45.11).abs() < 0.01, "{power}");
    // rxon cleared after the valid packet: the receiver is back in TUNE (0x07 = 0x02).
    assert_eq!(b.chip.state(), ChipState::Tune);
    assert_eq!(read(&mut b.spi, 0x07), 0x02);
    assert_eq!(a.chip.state(), ChipState::Tune);
    let trace = sim.medium().trace();
    assert_eq!(trace.len(), 1);
    assert_eq!(
        trace[0].outcome_at(b.id),
        Some(Outcome::Delivered { bit_errors: 0 })
    );
    assert!((trace[0].power_dbm[1] + 45.11).abs() < 0.01);
    assert_eq!(trace[0].receptions[0].power_dbm, trace[0].power_dbm[1]);
}

#[test]
fn airtime_matches_the_configuration() {
    let (sim, mut a, mut b) = pair(10.0);
    let got = exchange(
        &mut a,
        &mut b,
        &payload(16),
        true,
        Duration::from_millis(20),
    );
    assert!(got.valid);
    let frame = &sim.medium().trace()[0];
    // 6 B preamble + 4 sync + 4 header + 1 length + 16 payload + 2 CRC = 264 bits at
    // txdr 0x0EBF: 3775·10⁶/2¹⁶ = 57 601.93 bit/s = 4 583 179.6 ns → 4 583 180 ns.
    assert_eq!(frame.bytes.len(), 4 + 4 + 1 + 16 + 2);
    assert_eq!(frame.airtime(), Duration::from_nanos(4_583_180));
    // TX started one PLL settle (200 µs) after txon; 0x07 = 0x0A was written at t0.
    assert!((frame.bit_rate_bps - 57_601.93).abs() < 0.01);
    assert_eq!(a.chip.airtime(16), frame.airtime());
    // A 200-byte packet: 6 + 4 + 4 + 1 + 200 + 2 bytes = 1736 bits · 65536/3775 µs = 30 137 879.7 ns.
    assert_eq!(a.chip.airtime(200), Duration::from_nanos(30_137_880));
}

#[test]
fn packet_of_200_bytes_goes_through_both_64_byte_fifos() {
    let (sim, mut a, mut b) = pair(50.0);
    let data = payload(200);
    let got = exchange(&mut a, &mut b, &data, true, Duration::from_millis(60));
    assert!(got.sent && got.valid && !got.fifo_error_tx, "{got:?}");
    assert_eq!(got.data.len(), 200);
    assert_eq!(got.data, data);
    assert_eq!(sim.medium().trace()[0].bytes.len(), 4 + 4 + 1 + 200 + 2);
}

#[test]
fn tx_fifo_not_refilled_underflows_and_the_crc_catches_it() {
    let (sim, mut a, mut b) = pair(50.0);
    let data = payload(100);
    let got = exchange(&mut a, &mut b, &data, false, Duration::from_millis(40));
    assert!(got.fifo_error_tx, "{got:?}");
    assert!(got.sent, "the frame still ends with ipksent");
    assert!(got.crc_error && !got.valid, "{got:?}");
    let frame = &sim.medium().trace()[0];
    assert!(frame.damaged);
    assert!(matches!(
        frame.outcome_at(b.id),
        Some(Outcome::CrcError { .. })
    ));
}

#[test]
fn wrong_hop_channel_wrong_bit_rate_and_wrong_header_receive_nothing() {
    // Channel 1 is 40 kHz away: outside the 37.5 kHz AFC pull-in.
    let (sim, mut a, mut b) = pair(100.0);
    write(&mut b.spi, 0x79, &[1]);
    let got = exchange(&mut a, &mut b, &payload(8), true, Duration::from_millis(10));
    assert!(got.sent && !got.valid && !got.crc_error && got.data.is_empty());
    match sim.medium().trace()[0].outcome_at(b.id) {
        Some(Outcome::Mismatch(Mismatch::Frequency { offset_hz })) => {
            assert!((offset_hz + 40_000.0).abs() < 1e-6)
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(b.chip.state(), ChipState::Rx);

    // TX at 64 kbit/s (Tau Labs 0x6E/0x6F = 0x10/0x62) against a 57.6 kbit/s receiver.
    let (sim, mut a, mut b) = pair(100.0);
    write(&mut a.spi, 0x6E, &[0x10, 0x62]);
    let got = exchange(&mut a, &mut b, &payload(8), true, Duration::from_millis(10));
    assert!(got.sent && !got.valid);
    assert!(matches!(
        sim.medium().trace()[0].outcome_at(b.id),
        Some(Outcome::Mismatch(Mismatch::BitRate { .. }))
    ));

    // Header check: receiver expects 0x12345679.
    let (sim, mut a, mut b) = pair(100.0);
    write(&mut b.spi, 0x42, &[0x79]);
    let got = exchange(&mut a, &mut b, &payload(8), true, Duration::from_millis(10));
    assert!(got.sent && !got.valid && !got.crc_error);
    assert_eq!(
        sim.medium().trace()[0].outcome_at(b.id),
        Some(Outcome::HeaderMismatch)
    );
    assert_eq!(
        read(&mut b.spi, 0x02) & 0x10,
        0x10,
        "headerr in device status"
    );
}

#[test]
fn interference_burst_over_the_payload_gives_a_crc_error() {
    let (sim, mut a, mut b) = pair(1000.0);
    // Received signal at 1 km ≈ −65 dBm; a −60 dBm burst on the channel from 3 ms to 6 ms
    // covers most of the payload (TX starts 0.2 ms after txon, the payload 2.3 ms later).
    sim.medium().add_interference(Interference {
        start: Duration::from_millis(3),
        end: Duration::from_millis(6),
        center_hz: 430e6,
        bandwidth_hz: 100e3,
        power_dbm: -60.0,
    });
    let got = exchange(
        &mut a,
        &mut b,
        &payload(40),
        true,
        Duration::from_millis(20),
    );
    assert!(
        got.crc_error && !got.valid,
        "{got:?} {}",
        sim.medium().trace()[0]
    );
    match sim.medium().trace()[0].outcome_at(b.id) {
        Some(Outcome::CrcError { bit_errors }) => assert!(bit_errors > 5, "{bit_errors}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn out_of_range_is_too_weak_and_near_sensitivity_is_lossy() {
    // Sensitivity at 57.6 kbit/s is −121 + 10·log10(24) = −107.2 dBm. +20 dBm over 400 km
    // of free space at 430 MHz (137.16 dB) arrives at −117.16 dBm: 10 dB below.
    let (sim, mut a, mut b) = pair(400_000.0);
    let got = exchange(&mut a, &mut b, &payload(8), true, Duration::from_millis(10));
    assert!(!got.valid);
    assert_eq!(
        sim.medium().trace()[0].outcome_at(b.id),
        Some(Outcome::TooWeak)
    );
    let power = sim
        .medium()
        .received_power_dbm(RadioId(0), RadioId(1), 430e6, 20.0);
    assert!((power + 117.16).abs() < 0.01, "{power}");
}

#[test]
fn receiver_not_in_rx_is_recorded_as_not_listening() {
    let (sim, mut a, _b) = pair(10.0);
    start_tx(&mut a.spi, 4, &[1, 2, 3, 4]);
    a.delay.delay_ms(5);
    assert_eq!(status(&mut a.spi).0 & 0x04, 0x04);
    assert_eq!(
        sim.medium().trace()[0].outcome_at(RadioId(1)),
        Some(Outcome::NotListening)
    );
}

/// Send 10 bytes a → b after `tweak` changed the registers of (a, b); returns b's outcome,
/// what b found in its RX FIFO, and (ipkvalid, icrcerror) as bits 1, 0.
fn variant(tweak: impl Fn(&mut RadioHandle, &mut RadioHandle)) -> (Option<Outcome>, Vec<u8>, u8) {
    let (sim, mut a, mut b) = pair(100.0);
    tweak(&mut a, &mut b);
    let got = exchange(
        &mut a,
        &mut b,
        &payload(10),
        true,
        Duration::from_millis(10),
    );
    let s1 = (u8::from(got.valid) << 1) | u8::from(got.crc_error);
    (sim.medium().trace()[0].outcome_at(b.id), got.data, s1)
}

#[test]
fn fixed_length_without_header_and_every_crc_kind() {
    for crc in 0..4u8 {
        let (outcome, data, s1) = variant(|a, b| {
            for r in [a, b] {
                // Packet handler + CRC of kind `crc` over the data only; fixed length,
                // no header, 2-byte sync.
                write(&mut r.spi, 0x30, &[0xAC | crc]);
                write(&mut r.spi, 0x33, &[0x0A]);
                write(&mut r.spi, 0x3E, &[10]);
            }
        });
        assert_eq!(
            outcome,
            Some(Outcome::Delivered { bit_errors: 0 }),
            "crc kind {crc}"
        );
        assert_eq!(s1, 0b10);
        assert_eq!(data, payload(10));
    }
}

#[test]
fn mismatched_crc_kind_sync_word_or_whitening_fail() {
    // CCITT at the sender, CRC-16 at the receiver.
    let (outcome, _, s1) = variant(|_, b| write(&mut b.spi, 0x30, &[0x8D]));
    assert!(
        matches!(outcome, Some(Outcome::CrcError { bit_errors: 0 })),
        "{outcome:?}"
    );
    assert_eq!(s1, 0b01);
    // Receiver expects sync 2D D4 4B 5A.
    let (outcome, _, s1) = variant(|_, b| write(&mut b.spi, 0x39, &[0x5A]));
    assert_eq!(outcome, Some(Outcome::SyncMismatch));
    assert_eq!(s1, 0);
    // A 2-byte receiver sync (2D D4) finds the first half of the 4-byte one and reads 4B 59
    // as header: the header check fails.
    let (outcome, _, _) = variant(|_, b| write(&mut b.spi, 0x33, &[0x42]));
    assert_eq!(outcome, Some(Outcome::HeaderMismatch));
    // Whitening off at the receiver only: the de-whitened header is garbage.
    let (outcome, _, _) = variant(|_, b| write(&mut b.spi, 0x70, &[0x0C]));
    assert_eq!(outcome, Some(Outcome::HeaderMismatch));
}

#[test]
fn multi_packet_rx_stays_in_rx() {
    let (sim, mut a, mut b) = pair(100.0);
    start_rx(&mut b.spi);
    write(&mut b.spi, 0x08, &[0x10]); // rxmpk (start_rx's FIFO clear wrote 0x08 = 0)
    for n in 0..2u8 {
        start_tx(&mut a.spi, 4, &[n; 4]);
        a.delay.delay_ms(5);
        assert_eq!(status(&mut b.spi).0 & 0x02, 0x02, "packet {n}");
        assert_eq!(b.chip.state(), ChipState::Rx);
        assert_eq!(read(&mut b.spi, 0x07), 0x06);
    }
    assert_eq!(read_n(&mut b.spi, 0x7F, 8), vec![0, 0, 0, 0, 1, 1, 1, 1]);
    assert_eq!(sim.medium().trace_len(), 2);
}
