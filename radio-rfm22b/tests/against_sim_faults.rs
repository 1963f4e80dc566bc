//! The real driver against the virtual Si4432 when things go wrong: RX and TX timeouts at the
//! exact virtual time (also mid-packet), CRC errors from medium bit errors, an interference
//! burst, a collision and corrupted injected frames — reported as outcomes, never as a
//! corrupted packet — and the chip usable afterwards.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

#[path = "common/sim_bench.rs"]
mod bench;

use core::time::Duration;

use bench::*;
use radio_rfm22b::{Error, RxOutcome};
use si4432_sim::{ChipState, Interference, Outcome, PLL_SETTLE_NS};

/// After an operation the chip is in READY with interrupts off, nIRQ released and both
/// FIFOs empty.
fn assert_idle(node: &Node) {
    assert_eq!(node.chip.state(), ChipState::Ready);
    assert_eq!((node.chip.peek(0x05), node.chip.peek(0x06)), (0, 0));
    assert!(!node.chip.nirq_is_low());
    assert_eq!((node.chip.rx_fifo_len(), node.chip.tx_fifo_len()), (0, 0));
}

#[test]
fn rx_timeout_returns_at_the_exact_virtual_time_and_the_chip_still_receives() {
    let bench = Bench::new(4);
    let (a, b) = bench.link(config(57_600, 45_000));
    for timeout_us in [0, 1, 5_000, 123_457] {
        let (out, elapsed) = bench.op(&b, async move |r| {
            let mut buf = [0u8; 255];
            r.receive(&mut buf, timeout_us).await
        });
        assert_eq!(out.unwrap(), RxOutcome::Timeout);
        assert_eq!(elapsed, Duration::from_micros(u64::from(timeout_us)));
        assert_idle(&b);
    }
    // Nobody listening: the frame goes out, B (in READY) is recorded as not listening.
    let (sent, elapsed) = bench.op(&a, async |r| r.transmit(&[1, 2, 3], 20_000).await);
    sent.unwrap();
    assert_eq!(
        elapsed,
        Duration::from_nanos(PLL_SETTLE_NS) + a.chip.airtime(3)
    );
    assert_eq!(bench.last_outcome_at(&b), Some(Outcome::NotListening));

    let payload = pattern(16, 7);
    let x = bench.exchange(&a, &b, &payload, 20_000);
    assert_eq!(x.payload, payload);
    // The receive returned when the packet was complete: lead + settle + airtime.
    assert_eq!(
        x.rx_elapsed,
        Duration::from_micros(RX_LEAD_US)
            + Duration::from_nanos(PLL_SETTLE_NS)
            + a.chip.airtime(16)
    );
    assert_idle(&b);
}

#[test]
fn tx_timeout_cuts_the_packet_is_never_delivered_and_the_next_one_is() {
    let bench = Bench::new(5);
    let (a, b) = bench.link(config(57_600, 45_000));
    let long = pattern(255, 1);
    // 255 bytes at 57.6 kbit/s are ~36 ms on air; give TX only 10 ms.
    assert!(a.chip.airtime(255) > Duration::from_millis(35));
    let x = bench.exchange_with(&a, &b, &long, 10_000, 60_000);
    assert_eq!(x.sent, Err(Error::Timeout));
    assert_eq!(x.tx_elapsed, Duration::from_millis(10));
    assert!(
        !matches!(x.received, Ok(RxOutcome::Packet(_))),
        "a cut frame was delivered: {x:?}"
    );
    let frame = bench.last_frame().unwrap();
    assert!(frame.damaged);
    assert_eq!(
        frame.airtime(),
        Duration::from_millis(10) - Duration::from_nanos(PLL_SETTLE_NS)
    );
    assert_idle(&a);
    assert_idle(&b);

    let x = bench.exchange(&a, &b, &long, 60_000);
    x.sent.unwrap();
    assert_eq!(x.payload, long);
}

#[test]
fn bit_errors_give_crc_error_outcomes_never_a_corrupted_packet() {
    let bench = Bench::new(21);
    let (a, b) = bench.link(config(57_600, 45_000));
    // 1 dB below the 57.6 kbit/s sensitivity (−107.2 dBm): a mix of clean packets, CRC
    // errors and lost sync words.
    let extra_db = bench.link_power_dbm(&a, &b) + 108.2;
    bench.medium.set_attenuation(a.id, b.id, extra_db);
    let (mut packets, mut crc_errors, mut lost) = (0, 0, 0);
    for i in 0..60u8 {
        let payload = pattern(16, i);
        // Long enough for a frame whose length byte was corrupted to 255 (≈ 37 ms).
        let x = bench.exchange(&a, &b, &payload, 60_000);
        x.sent.unwrap();
        let medium_says = bench.last_outcome_at(&b).unwrap();
        match (x.received.unwrap(), medium_says) {
            (RxOutcome::Packet(p), Outcome::Delivered { .. }) => {
                assert_eq!((p.len, &x.payload), (16, &payload));
                // −108.2 dBm of signal plus the noise floor, read in 0.5 dB steps.
                assert!((-109..=-106).contains(&p.signal.rssi_dbm), "{p:?}");
                packets += 1;
            }
            (RxOutcome::CrcError(signal), Outcome::CrcError { bit_errors }) => {
                assert!(bit_errors > 0);
                assert!((-109..=-106).contains(&signal.rssi_dbm), "{signal:?}");
                crc_errors += 1;
            }
            (RxOutcome::Timeout, Outcome::SyncCorrupted | Outcome::HeaderMismatch) => lost += 1,
            (driver, medium) => panic!("packet {i}: driver {driver:?}, medium {medium:?}"),
        }
        assert_idle(&b);
    }
    println!("60 packets at -108.2 dBm: {packets} valid, {crc_errors} CRC errors, {lost} lost");
    assert_eq!(packets + crc_errors + lost, 60);
    assert!(
        packets >= 15 && crc_errors >= 10,
        "{packets}/{crc_errors}/{lost}"
    );

    // The obstacle goes away: the next packet is clean, at the free-space level again.
    bench.medium.set_attenuation(a.id, b.id, 0.0);
    let payload = pattern(16, 0xEE);
    let x = bench.exchange(&a, &b, &payload, 20_000);
    assert_eq!(x.payload, payload);
    assert!((f64::from(x.packet().signal.rssi_dbm) - bench.link_power_dbm(&a, &b)).abs() < 1.5);
}

#[test]
fn an_interference_burst_over_the_payload_is_a_crc_error_then_the_link_recovers() {
    let bench = Bench::new(6);
    let (a, b) = bench.link(config(57_600, 45_000));
    // The frame starts RX_LEAD_US + 200 µs after the exchange begins; preamble (40 bits),
    // sync (16) and length (8) take 1.11 ms, the 16-byte payload the next 2.22 ms. A −55 dBm
    // burst (10 dB over the −65 dBm signal) from 1.5 to 2.5 ms into the frame hits only it.
    let frame_start = bench.now() + Duration::from_micros(RX_LEAD_US + PLL_SETTLE_NS / 1_000);
    bench.medium.add_interference(Interference {
        start: frame_start + Duration::from_micros(1_500),
        end: frame_start + Duration::from_micros(2_500),
        center_hz: f64::from(CARRIER_HZ),
        bandwidth_hz: 100e3,
        power_dbm: -55.0,
    });
    let payload = pattern(16, 3);
    let x = bench.exchange(&a, &b, &payload, 20_000);
    x.sent.unwrap();
    let Ok(RxOutcome::CrcError(signal)) = x.received else {
        panic!("expected a CRC error: {x:?}");
    };
    // RSSI was latched at sync, before the burst.
    assert!((f64::from(signal.rssi_dbm) - bench.link_power_dbm(&a, &b)).abs() < 1.5);
    let Some(Outcome::CrcError { bit_errors }) = bench.last_outcome_at(&b) else {
        panic!("{:?}", bench.last_frame());
    };
    // About 58 bits lie under the burst at BER ≈ 0.3; every hit byte has one flipped bit.
    assert!((5..=58).contains(&bit_errors), "{bit_errors}");
    assert!(x.payload.is_empty());
    // The driver gave up at the end of the frame, not at its timeout.
    assert_eq!(
        x.rx_elapsed,
        Duration::from_micros(RX_LEAD_US)
            + Duration::from_nanos(PLL_SETTLE_NS)
            + a.chip.airtime(16)
    );
    assert_idle(&b);

    let x = bench.exchange(&a, &b, &payload, 20_000);
    assert_eq!(x.payload, payload);
    assert_eq!(
        bench.last_outcome_at(&b),
        Some(Outcome::Delivered { bit_errors: 0 })
    );
}

#[test]
fn a_deadline_in_the_middle_of_a_packet_never_gives_half_a_packet() {
    let bench = Bench::new(7);
    let (a, b) = bench.link(config(9_600, 30_000));
    let payload = pattern(200, 8);
    // The 200-byte frame lasts ~174 ms at 9.6 kbit/s; B's deadline falls 50 ms into it,
    // after sync and several FIFO drains.
    let timeout_us = (RX_LEAD_US + PLL_SETTLE_NS / 1_000 + 50_000) as u32;
    let x = bench.exchange(&a, &b, &payload, timeout_us);
    x.sent.unwrap();
    let frame_end = Duration::from_micros(RX_LEAD_US)
        + Duration::from_nanos(PLL_SETTLE_NS)
        + a.chip.airtime(200);
    // Either policy is sound: stop at the deadline (the frame is aborted), or let a packet
    // whose sync came in time complete. Never a partial payload.
    match x.received.unwrap() {
        RxOutcome::Timeout => {
            assert_eq!(x.rx_elapsed, Duration::from_micros(u64::from(timeout_us)));
            assert_eq!(bench.last_outcome_at(&b), Some(Outcome::Aborted));
        }
        RxOutcome::Packet(p) => {
            assert_eq!((p.len, &x.payload), (200, &payload));
            assert_eq!(x.rx_elapsed, frame_end);
        }
        other => panic!("{other:?}"),
    }
    assert_idle(&b);
    let x = bench.exchange(&a, &b, &payload, 400_000);
    assert_eq!(x.payload, payload);
}

#[test]
fn a_collision_is_a_crc_error_at_the_receiver_never_a_mixed_packet() {
    let bench = Bench::new(8);
    let config = config(57_600, 45_000);
    let (a, b) = bench.link(config);
    // C is as far from B as A is, so neither frame can capture the receiver.
    let c = bench.node_at([DISTANCE_M, DISTANCE_M, 0.0]);
    bench.init(&c, config).unwrap();
    let receiver = b.clone();
    let listen = bench.sim.spawn(async move {
        receiver
            .with(async |r| {
                let mut buf = [0u8; 255];
                r.receive(&mut buf, 50_000).await
            })
            .await
    });
    // A starts at 1 ms; C 1.5 ms later, after A's sync word, over A's payload.
    let mut senders = Vec::new();
    for (node, lead_us, fill) in [(&a, RX_LEAD_US, 0xA5), (&c, RX_LEAD_US + 1_500, 0x5A)] {
        let node = node.clone();
        let lead = bench.pause(lead_us);
        senders.push(bench.sim.spawn(async move {
            lead.await;
            node.with(async |r| r.transmit(&[fill; 32], TX_TIMEOUT_US).await)
                .await
        }));
    }
    assert!(bench.sim.run_until_or(RUN_LIMIT, || {
        listen.is_finished() && senders.iter().all(|s| s.is_finished())
    }));
    for s in &senders {
        s.take().unwrap().unwrap();
    }
    let Ok(RxOutcome::CrcError(_)) = listen.take().unwrap() else {
        panic!("{:?}", bench.medium.trace());
    };
    let trace = bench.medium.trace();
    let [first, second] = &trace[trace.len() - 2..] else {
        panic!("expected two frames")
    };
    assert!(matches!(
        first.outcome_at(b.id),
        Some(Outcome::CrcError { bit_errors }) if bit_errors > 0
    ));
    assert_eq!(second.outcome_at(b.id), Some(Outcome::Busy));
    assert_idle(&b);
    // The air is clear again: A's next packet arrives intact.
    let x = bench.exchange(&a, &b, &[0xA5; 32], 20_000);
    assert_eq!(x.payload, vec![0xA5; 32]);
}

/// B listens for 50 ms; 1 ms in, an ideal transmitter injects `payload` at `power_dbm`.
fn receive_injected(bench: &Bench, b: &Node, payload: &[u8], power_dbm: f64) -> RxOutcome {
    let medium = bench.medium.clone();
    let (id, payload) = (b.id, payload.to_vec());
    let lead = bench.pause(RX_LEAD_US);
    bench.sim.spawn(async move {
        lead.await;
        medium.inject_packet(id, &payload, power_dbm).unwrap();
    });
    let (out, _) = bench.op(b, async |r| {
        let mut buf = [0u8; 255];
        let out = r.receive(&mut buf, 50_000).await;
        if let Ok(RxOutcome::Packet(p)) = out {
            assert_eq!(&buf[..p.len], pattern(p.len, 0x33).as_slice());
        }
        out
    });
    out.unwrap()
}

#[test]
fn injected_frames_clean_then_under_a_burst_then_clean() {
    let bench = Bench::new(9);
    let b = bench.node_at([0.0; 3]);
    bench.init(&b, config(128_000, 90_000)).unwrap();
    // A clean frame from an ideal transmitter in B's own format, at −80 dBm.
    let RxOutcome::Packet(p) = receive_injected(&bench, &b, &pattern(120, 0x33), -80.0) else {
        panic!("{:?}", bench.last_frame());
    };
    assert_eq!(p.len, 120);
    assert!((-81..=-79).contains(&p.signal.rssi_dbm), "{p:?}");
    assert_eq!(p.signal.afc_offset_hz, 0);
    // The same frame (8.125 ms on air) under a burst 20 dB stronger from 1 ms to 8 ms in.
    let start = bench.now() + Duration::from_micros(RX_LEAD_US);
    bench.medium.add_interference(Interference {
        start: start + Duration::from_millis(1),
        end: start + Duration::from_millis(8),
        center_hz: f64::from(CARRIER_HZ),
        bandwidth_hz: 200e3,
        power_dbm: -60.0,
    });
    let outcome = receive_injected(&bench, &b, &pattern(120, 0x33), -80.0);
    assert!(matches!(outcome, RxOutcome::CrcError(_)), "{outcome:?}");
    assert!(matches!(
        bench.last_outcome_at(&b),
        Some(Outcome::CrcError { bit_errors }) if bit_errors > 20
    ));
    assert_idle(&b);
    // Burst over: clean again.
    let outcome = receive_injected(&bench, &b, &pattern(16, 0x33), -80.0);
    assert!(
        matches!(outcome, RxOutcome::Packet(p) if p.len == 16),
        "{outcome:?}"
    );
}

/// nIRQ stuck low (an unpowered or browned-out module can read that way) or stuck high,
/// on a bus with its real SPI time: every receive and transmit returns by its deadline (plus
/// the SPI time of the status read in flight and of the clean-up), and the chip works again
/// once the line does.
#[test]
fn a_stuck_nirq_line_never_outlasts_a_deadline() {
    use si4432_sim::{Fault, RadioConfig};
    let bench = Bench::new(12);
    let a = bench.node(RadioConfig::at([0.0, 0.0, 0.0]));
    let b = bench.node(RadioConfig::at([DISTANCE_M, 0.0, 0.0]));
    let config = config(57_600, 45_000);
    bench.init(&a, config).unwrap();
    bench.init(&b, config).unwrap();
    // Clean-up after a timeout: a handful of register writes at 5.25 MHz.
    let slack = Duration::from_micros(200);
    for fault in [Fault::NirqStuckLow, Fault::NirqStuckHigh] {
        b.chip.set_fault(fault);
        let (out, elapsed) = bench.op(&b, async |r| {
            let mut buf = [0u8; 64];
            r.receive(&mut buf, 5_000).await
        });
        assert_eq!(out.unwrap(), RxOutcome::Timeout, "{fault:?}");
        assert!(
            elapsed >= Duration::from_millis(5) && elapsed < Duration::from_millis(5) + slack,
            "{fault:?}: receive took {elapsed:?}"
        );
        let (sent, elapsed) = bench.op(&b, async |r| r.transmit(&[1, 2, 3], 10_000).await);
        assert!(
            elapsed < Duration::from_millis(10) + slack,
            "{fault:?}: {elapsed:?}"
        );
        match fault {
            // The packet goes out; with the line stuck low the driver sees `ipksent` in
            // the status it keeps reading.
            Fault::NirqStuckLow => sent.unwrap(),
            // Nothing ever signals the end: a TX timeout.
            _ => assert!(matches!(sent, Err(Error::Timeout)), "{sent:?}"),
        }
        b.chip.set_fault(Fault::None);
        let x = bench.exchange(&a, &b, &[7, 8, 9], 20_000);
        x.sent.as_ref().unwrap();
        assert_eq!(x.payload, [7, 8, 9], "{fault:?}");
    }
}
