//! The real driver against the virtual Si4432: what a receiver must not hear. Another hop
//! channel, another carrier, another bit rate, a foreign sync word or header → the driver
//! times out at its deadline (the medium says why), and once the settings match again the
//! packet arrives.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

#[path = "common/sim_bench.rs"]
mod bench;

use core::time::Duration;

use bench::*;
use radio_rfm22b::{Carrier, PacketConfig, RxOutcome};
use si4432_sim::Outcome;
use si4432_sim::modem::Mismatch;

const RX_TIMEOUT_US: u32 = 20_000;

/// `from` sends to `to`, which must time out; returns what the medium recorded at `to`.
/// Without a sync word the timeout is exact. A header-rejected packet did show its sync
/// word, and a driver may give a started packet the airtime of the longest one (+2 ms) to
/// complete, so there the bound is that.
fn not_received(bench: &Bench, from: &Node, to: &Node) -> Outcome {
    let x = bench.exchange(from, to, &pattern(16, 9), RX_TIMEOUT_US);
    x.sent.unwrap();
    assert_eq!(x.received.unwrap(), RxOutcome::Timeout);
    let outcome = bench.last_outcome_at(to).unwrap();
    let timeout = Duration::from_micros(u64::from(RX_TIMEOUT_US));
    if outcome == Outcome::HeaderMismatch {
        // 2 ms of the driver's margin plus 1 ms for its airtime at the nominal bit rate.
        let bound = timeout + to.chip.airtime(255) + Duration::from_millis(3);
        assert!(
            x.rx_elapsed >= timeout && x.rx_elapsed <= bound,
            "{:?}",
            x.rx_elapsed
        );
    } else {
        assert_eq!(x.rx_elapsed, timeout, "{outcome:?}");
    }
    outcome
}

/// `from` sends to `to`, which must get the exact payload.
fn received(bench: &Bench, from: &Node, to: &Node) -> radio_rfm22b::RxPacket {
    let payload = pattern(16, 10);
    let x = bench.exchange(from, to, &payload, RX_TIMEOUT_US);
    assert_eq!(x.payload, payload);
    x.packet()
}

#[test]
fn another_hop_channel_is_not_received() {
    let bench = Bench::new(30);
    let (a, b) = bench.link(config(57_600, 45_000));
    // Channel 20 with 10 kHz spacing: B listens 200 kHz above A.
    bench.op(&b, async |r| r.set_channel(20).await).0.unwrap();
    let Outcome::Mismatch(Mismatch::Frequency { offset_hz }) = not_received(&bench, &a, &b) else {
        panic!("{:?}", bench.last_frame());
    };
    assert!((offset_hz + 200_000.0).abs() < 1.0, "{offset_hz}");
    // A follows B to channel 20: received, on 433.2 MHz.
    bench.op(&a, async |r| r.set_channel(20).await).0.unwrap();
    received(&bench, &a, &b);
    let carrier_hz = bench.last_frame().unwrap().carrier_hz;
    assert!((carrier_hz - 433.2e6).abs() < 1.0, "{carrier_hz}");
}

#[test]
fn another_carrier_is_not_received() {
    let bench = Bench::new(31);
    let (a, b) = bench.link(config(57_600, 45_000));
    bench
        .op(&b, async |r| r.set_carrier(Carrier::new(434_000_000)).await)
        .0
        .unwrap();
    let Outcome::Mismatch(Mismatch::Frequency { offset_hz }) = not_received(&bench, &a, &b) else {
        panic!("{:?}", bench.last_frame());
    };
    assert!((offset_hz + 1e6).abs() < 1.0, "{offset_hz}");
    // 30 kHz off is inside the 57.6 kbit/s AFC pull-in: received, AFC reports the offset.
    bench
        .op(&b, async |r| r.set_carrier(Carrier::new(433_030_000)).await)
        .0
        .unwrap();
    let p = received(&bench, &a, &b);
    assert!((p.signal.afc_offset_hz + 30_000).abs() <= 157, "{p:?}");
    // The same carrier again: no offset.
    bench
        .op(&b, async |r| r.set_carrier(Carrier::new(CARRIER_HZ)).await)
        .0
        .unwrap();
    assert_eq!(received(&bench, &a, &b).signal.afc_offset_hz, 0);
}

#[test]
fn another_bit_rate_is_not_received() {
    let bench = Bench::new(32);
    let (a, b) = bench.link(config(57_600, 45_000));
    for (rate, deviation) in [(19_200, 45_000), (64_000, 45_000), (128_000, 90_000)] {
        bench
            .op(&b, async move |r| r.apply(config(rate, deviation)).await)
            .0
            .unwrap();
        match not_received(&bench, &a, &b) {
            Outcome::Mismatch(Mismatch::BitRate { tx_bps, rx_bps }) => {
                assert!((tx_bps - 57_600.0).abs() < 10.0, "{tx_bps}");
                assert!((rx_bps - f64::from(rate)).abs() / f64::from(rate) < 0.01);
            }
            other => panic!("{rate}: {other:?}"),
        }
    }
    bench
        .op(&b, async |r| r.apply(config(57_600, 45_000)).await)
        .0
        .unwrap();
    received(&bench, &a, &b);
}

#[test]
fn a_foreign_sync_word_is_not_received() {
    let bench = Bench::new(33);
    let (a, b) = bench.link(config(57_600, 45_000));
    // A foreign link that uses a different two-byte sync word, then a four-byte one that
    // starts like ours (the chip searches for all of its own sync word).
    for (word, len) in [([0xAA, 0x55, 0, 0], 2), ([0x2D, 0xD4, 0x12, 0x34], 4)] {
        let foreign = config_with(
            57_600,
            45_000,
            PacketConfig::new().with_sync_word(word, len),
        );
        bench
            .op(&b, async move |r| r.apply(foreign).await)
            .0
            .unwrap();
        assert_eq!(not_received(&bench, &a, &b), Outcome::SyncMismatch);
    }
    bench
        .op(&b, async |r| r.apply(config(57_600, 45_000)).await)
        .0
        .unwrap();
    received(&bench, &a, &b);
}

#[test]
fn a_foreign_header_is_not_received_and_ours_is_reported() {
    const OURS: [u8; 4] = *b"TL\x01\x02";
    const THEIRS: [u8; 4] = *b"TL\x07\x02";
    let bench = Bench::new(34);
    let sender = PacketConfig::new().with_header(OURS, 4);
    let a = bench.node_at([0.0; 3]);
    let b = bench.node_at([DISTANCE_M, 0.0, 0.0]);
    bench.init(&a, config_with(57_600, 45_000, sender)).unwrap();
    // B checks all four header bytes against another link's id.
    let checking = sender.with_header_check(THEIRS, [0xFF; 4], 0x0F, 0x00);
    bench
        .init(&b, config_with(57_600, 45_000, checking))
        .unwrap();
    assert_eq!(not_received(&bench, &a, &b), Outcome::HeaderMismatch);
    // Expecting our own id instead, the packet passes and its header is reported.
    bench
        .op(&b, async |r| r.set_check_header(OURS).await)
        .0
        .unwrap();
    let p = received(&bench, &a, &b);
    assert_eq!(p.header, OURS);
    // Broadcast on the third byte: 0xFF there is accepted even though 0x01 is expected.
    let broadcast = sender.with_header_check(OURS, [0xFF; 4], 0x0F, 0x02);
    bench
        .op(&b, async move |r| {
            r.apply(config_with(57_600, 45_000, broadcast)).await
        })
        .0
        .unwrap();
    bench
        .op(&a, async |r| r.set_tx_header(*b"TL\xFF\x02").await)
        .0
        .unwrap();
    assert_eq!(received(&bench, &a, &b).header, *b"TL\xFF\x02");
    // Neither ours nor broadcast: rejected.
    bench
        .op(&a, async |r| r.set_tx_header(THEIRS).await)
        .0
        .unwrap();
    assert_eq!(not_received(&bench, &a, &b), Outcome::HeaderMismatch);
}
