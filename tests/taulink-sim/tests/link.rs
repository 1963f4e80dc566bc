//! The link tests, both ends in one simulated medium in virtual time.

use taulink_sim::{Scenario, run, simulate};
use telemetry::channels::ChannelFormat;
use telemetry::link::{HOP_CHANNELS, HopSequence, RateMode};

fn quick(rate: RateMode, seconds: f64) -> Scenario {
    Scenario {
        rate,
        duration_s: seconds,
        ..Scenario::default()
    }
}

#[test]
fn bind_over_the_air_stores_the_same_parameters() {
    for rate in RateMode::ALL {
        let s = Scenario {
            telemetry_load: false,
            ..quick(rate, 3.0)
        };
        let o = simulate(&s, |_| {});
        let bound = o.main.bound_us.expect("follower bound");
        // Master starts offering at 0.3 s; one offer (≈11 ms at 19.2 kbps) plus accepts.
        // 2.6 s of link at 1:4 telemetry, minus acquisition (≤ one dwell of 33 slots).
        assert!(bound < 400_000, "{rate:?}: bound at {bound} µs");
        assert_eq!(o.main.follower_params, Some(o.params));
        assert!(
            o.main.outputs_ok > 50,
            "{rate:?}: {} outputs",
            o.main.outputs_ok
        );
    }
}

#[test]
fn sixteen_channels_arrive_unchanged() {
    let o = simulate(&quick(RateMode::F500, 5.0), |_| {});
    // Every output is compared with the handset sample it carries, all 16 channels.
    assert_eq!(o.main.outputs_bad, 0);
    // 500 slots/s, 1 in 4 downlink, from ~0.4 s on.
    assert!(o.main.outputs_ok > 1600, "{}", o.main.outputs_ok);
    let compact = Scenario {
        format: ChannelFormat::Compact8,
        ..quick(RateMode::L50, 5.0)
    };
    let o = simulate(&compact, |_| {});
    assert_eq!(o.main.outputs_bad, 0);
    // 37.5 updates/s for ≈4.6 s, minus acquisition (up to one 660 ms dwell).
    assert!(o.main.outputs_ok > 120, "{}", o.main.outputs_ok);
}

#[test]
fn both_ends_follow_the_same_hop_sequence() {
    let o = simulate(&quick(RateMode::F250, 10.0), |_| {});
    let hops = HopSequence::new(o.params.bind_id);
    // The master's sequence is the bind ID's permutation, one hop per slot.
    assert!(o.main.master_hops.len() > 2000);
    for &(slot, ch) in &o.main.master_hops {
        assert_eq!(ch, hops.channel(usize::from(slot) % HOP_CHANNELS));
    }
    // The follower tracked the same channel in the same slot, over every channel.
    let mut visited = [false; HOP_CHANNELS];
    assert!(o.main.follower_hops.len() > 2000);
    for &(slot, ch) in &o.main.follower_hops {
        assert_eq!(ch, hops.channel(usize::from(slot) % HOP_CHANNELS));
        visited[usize::from(ch)] = true;
    }
    assert!(visited.iter().all(|v| *v));
}

#[test]
fn a_megabyte_each_way_through_ten_percent_loss_arrives_intact_and_in_order() {
    // F250, compact channels, every other slot downlink: ≈2.4 kB/s up and ≈3.6 kB/s down
    // through 10 % loss (41-byte frames since the slot budget charges the SPI set-up), so
    // 1 MB each way takes ≈430 s of virtual time (about a second of real time in a release
    // build, a few in the opt-level-1 dev profile).
    let s = Scenario {
        rate: RateMode::F250,
        format: ChannelFormat::Compact8,
        telemetry_ratio: 2,
        loss: 0.1,
        duration_s: 480.0,
        ..Scenario::default()
    };
    let o = simulate(&s, |_| {});
    let m = &o.main;
    // Every byte is checked against the sender's stream at its position: a duplicate, a
    // gap or a reordering would show up as a wrong byte.
    assert_eq!((m.up_bytes_bad, m.down_bytes_bad), (0, 0));
    assert!(m.up_bytes_ok >= 1_000_000, "uplink {} B", m.up_bytes_ok);
    assert!(
        m.down_bytes_ok >= 1_000_000,
        "downlink {} B",
        m.down_bytes_ok
    );
    assert!(
        o.medium.lost_random > 10_000,
        "loss was injected: {:?}",
        o.medium
    );
}

#[test]
fn link_cut_gives_failsafe_within_the_configured_time_then_recovery() {
    for (rate, failsafe_ms) in [
        (RateMode::F500, 250),
        (RateMode::F250, 100),
        (RateMode::L50, 250),
    ] {
        let s = Scenario {
            cut_s: Some((5.0, 7.0)),
            failsafe_ms,
            ..quick(rate, 10.0)
        };
        let o = simulate(&s, |_| {});
        let changes = &o.main.failsafe_changes;
        // Out of the boot failsafe once bound, into failsafe once (the cut), out again.
        assert_eq!(
            changes.iter().map(|c| c.1).collect::<Vec<_>>(),
            vec![false, true, false],
            "{rate:?}: {changes:?}"
        );
        let (entered, left) = (changes[1].0, changes[2].0);
        // A 2 s cut is longer than 32 missed uplinks at every rate: tracking was given up
        // and the master re-acquired by scanning.
        assert_eq!(o.main.now.resyncs, 1, "{rate:?}");
        // Declared `failsafe_ms` after the last valid update (a radio operation in progress
        // — a downlink being sent — may delay it by at most one slot).
        let silence = o.main.silence_before_failsafe_us[0];
        let slot_us = u64::from(rate.slot_us());
        assert!(
            (failsafe_ms * 1000..=failsafe_ms * 1000 + slot_us).contains(&silence),
            "{rate:?}: {silence} µs of silence"
        );
        let slot = u64::from(rate.slot_us());
        // The last packet arrived between 2 slots before the cut (one may be a downlink
        // slot) and one airtime after it (a packet already on the air when the path was
        // cut); failsafe is declared at the first slot boundary `failsafe_ms` after it.
        assert!(
            entered >= 5_000_000 + failsafe_ms * 1000 - 2 * slot,
            "{rate:?}: {entered}"
        );
        assert!(
            entered <= 5_000_000 + failsafe_ms * 1000 + 2 * slot,
            "{rate:?}: {entered}"
        );
        // Recovery: at most one dwell (a hop cycle + 1 slot) per channel tried, plus one
        // hop cycle for the master to come round.
        let bound = 7_000_000 + 3 * (HOP_CHANNELS as u64 + 1) * slot;
        assert!(
            left > 7_000_000 && left < bound,
            "{rate:?}: recovered at {left}"
        );
        assert_eq!(o.main.outputs_bad, 0);
    }
}

#[test]
fn two_links_in_one_medium_never_accept_each_others_packets() {
    // Worst case for the link layer: header checking off, so every foreign packet on a
    // shared channel reaches the link decoder and only the keyed CRC stands in the way.
    for header_check in [false, true] {
        let s = Scenario {
            foreign_link: true,
            header_check,
            bind: false,
            ..quick(RateMode::F500, 105.0)
        };
        let r = run(&s, |_| {});
        assert!(r.transmitted >= 100_000, "{}", r.transmitted);
        assert_eq!(r.errors, 0);
        assert_eq!(r.foreign_errors, 0);
        if header_check {
            assert!(
                r.header_rejected > 0,
                "foreign packets were heard and dropped in hardware"
            );
        } else {
            assert!(
                r.link_rejected > 0,
                "foreign packets were heard and rejected by the CRC"
            );
        }
        assert!(r.uplink_lq > 80, "{}", r.uplink_lq);
    }
}

#[test]
fn default_run_reports_sane_figures() {
    let r = run(&Scenario::default(), |_| {});
    assert_eq!(r.errors, 0);
    // F250, 1:4 telemetry: 187.5 channel updates/s.
    assert!(
        (r.update_rate_hz - 187.5).abs() < 2.0,
        "{}",
        r.update_rate_hz
    );
    assert_eq!((r.uplink_lq, r.downlink_lq), (100, 100));
    // Latency: ≤ 1 ms sample age + up to 2 slots waiting + 3 ms lead/settle/airtime.
    assert!(
        r.latency_mean_ms > 3.0 && r.latency_p99_ms < 12.5,
        "{} {}",
        r.latency_mean_ms,
        r.latency_p99_ms
    );
    assert!(r.to_json().contains("\"update_rate_hz\": 18"));
}

#[test]
fn packet_level_bit_errors_without_chip_crc_never_reach_the_outputs() {
    // The packet-level medium can turn the chip CRC off: every corrupted packet then
    // reaches the link decoder, which must reject all of them.
    let s = Scenario {
        chip_level: false,
        chip_crc: false,
        bit_error_rate: 2e-3,
        ..quick(RateMode::F500, 30.0)
    };
    let o = simulate(&s, |_| {});
    assert!(o.medium.corrupted_delivered > 1_000, "{:?}", o.medium);
    assert_eq!(
        (
            o.main.outputs_bad,
            o.main.up_bytes_bad,
            o.main.down_bytes_bad
        ),
        (0, 0, 0)
    );
    assert!(o.main.outputs_ok > 1_000);
}
