//! The latency goals of issue 17 as measured figures (chip level, SPI time and nIRQ latency
//! on, 30 s, seed 1): the stick mode F700 at 1:8 telemetry with an EdgeTX handset that
//! follows the module's timing frames and with free-running PPM (through the module's own
//! decoder), and every older mode keeping the figures it had before channels were latched
//! at transmission (spec §10).

use taulink_sim::handset::HandsetKind;
use taulink_sim::{Report, Scenario, run};
use telemetry::channels::ChannelFormat;
use telemetry::link::RateMode;

fn f700(handset: HandsetKind) -> Report {
    let r = run(
        &Scenario {
            rate: RateMode::F700,
            telemetry_ratio: 8,
            format: ChannelFormat::Sticks16,
            handset,
            ..Scenario::default()
        },
        |_| {},
    );
    assert_eq!(r.errors, 0);
    r
}

#[test]
fn f700_updates_the_sticks_600_times_a_second_every_channel_100_and_carries_1kb_each_way() {
    let r = f700(HandsetKind::CrsfSynced);
    // 700 slots/s, 7 in 8 uplinks: 612.5 stick updates/s, every aux channel in 1 of 4.
    assert!(r.stick_updates_per_s >= 600.0, "{}", r.stick_updates_per_s);
    assert!(
        r.all_channel_updates_per_s >= 100.0,
        "{}",
        r.all_channel_updates_per_s
    );
    assert!(r.uplink_goodput_bps >= 1_000.0, "{}", r.uplink_goodput_bps);
    assert!(
        r.downlink_goodput_bps >= 1_000.0,
        "{}",
        r.downlink_goodput_bps
    );
    assert_eq!((r.uplink_lq, r.downlink_lq), (100, 100));
}

#[test]
fn f700_with_a_synced_crsf_handset_has_a_p99_latency_under_2_5_ms() {
    let r = f700(HandsetKind::CrsfSynced);
    // The handset really followed the timing frames (5 a second).
    assert!(r.handset_corrections >= 100, "{}", r.handset_corrections);
    assert!(r.latency_p99_ms <= 2.5, "{}", r.latency_p99_ms);
    // Measured 1.96 / 2.00 ms (mean / p99) with the latch after the transmitter comes on
    // (2.30 / 2.35 before).
    assert!(r.latency_p99_ms <= 2.05, "{}", r.latency_p99_ms);
    // Synced, every frame waits the same: the spread is the mixer's jitter.
    assert!(r.latency_p99_ms - r.latency_mean_ms < 0.2);
}

#[test]
fn f700_with_free_running_ppm_has_a_p99_latency_under_4_ms() {
    // The sticks (the stamp rides in channels 1–3), from the frame's last channel edge at
    // the module's input to the follower's output, every frame counted. A pilot's frame
    // agrees with the one before (within 200 µs on every channel) and the module's decoder
    // releases it at that edge; a switch flip waits for its sync gap (2.5 ms; held frames
    // are in the figure). Then the wait for the next latch (up to two slots across the
    // downlink slot) and the path from the latch, which comes once the transmitter is on.
    // Measured 1.91 / 3.77 ms (mean / p99), 99.6 % released early; 4.78 / 6.58 ms when every
    // frame waited for its sync gap, 2.25 / 4.13 ms with the latch before the SPI set-up.
    let r = f700(HandsetKind::Ppm);
    assert!(
        r.ppm_early_release_pct >= 99.0,
        "{}",
        r.ppm_early_release_pct
    );
    assert!(r.ppm_early_release_pct < 100.0, "switch flips are held");
    assert!(r.latency_p99_ms <= 3.9, "{}", r.latency_p99_ms);
    assert!(r.latency_mean_ms <= 2.0, "{}", r.latency_mean_ms);
}

#[test]
fn the_older_modes_keep_or_improve_their_latency() {
    // (mode, format, p99 and mean in ms before, with the same 1 kHz free-running samples.)
    for (rate, format, p99, mean) in [
        (RateMode::L50, ChannelFormat::Compact8, 58.8, 34.6),
        (RateMode::M100, ChannelFormat::Full16, 29.6, 17.4),
        (RateMode::F250, ChannelFormat::Full16, 11.7, 6.9),
        (RateMode::F500, ChannelFormat::Full16, 5.8, 3.4),
    ] {
        let r = run(
            &Scenario {
                rate,
                format,
                handset: HandsetKind::Free1k,
                ..Scenario::default()
            },
            |_| {},
        );
        assert_eq!(r.errors, 0);
        assert!(r.latency_p99_ms <= p99, "{rate:?}: {}", r.latency_p99_ms);
        assert!(r.latency_mean_ms <= mean, "{rate:?}: {}", r.latency_mean_ms);
        // and they carry every channel in every uplink
        assert!((r.stick_updates_per_s - r.all_channel_updates_per_s).abs() < 0.01);
    }
}
