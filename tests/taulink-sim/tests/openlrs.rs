//! `--protocol openlrs38|openlrs39`: the crate's OpenLRSng TX role flies its RX role on the
//! virtual chips and the report carries the OpenLRSng figures, at the default profile
//! (19200 bit/s, 8 channels, 25 ms) and the fastest (125000 bit/s, 16 channels, 7 ms).
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use clap::Parser;
use openlrs::BindingVersion;
use taulink_sim::Cli;
use taulink_sim::openlrs::{OpenLrsScenario, run};

fn scenario(args: &str) -> Result<Option<OpenLrsScenario>, String> {
    Cli::try_parse_from(std::iter::once("taulink-sim").chain(args.split_whitespace()))
        .map_err(|e| e.to_string())?
        .openlrs()
}

#[test]
fn default_profile_figures() {
    let s = scenario("--protocol openlrs38 --duration 12 --cut 6:8")
        .unwrap()
        .unwrap();
    assert_eq!(s.version, BindingVersion::V38);
    let r = run(&s);
    assert!(r.bound && !r.failed(), "{r:?}");
    assert_eq!(
        (r.bit_rate_bps, r.interval_us, r.channels),
        (19_200, 25_000, 8)
    );
    // One update per 25 ms interval.
    assert!((38.0..=40.1).contains(&r.update_rate_hz), "{r:?}");
    // Uplink airtime and the telemetry reply, plus at most one 2 ms handset step.
    assert!((15.0..25.0).contains(&r.latency_mean_ms), "{r:?}");
    assert!(r.latency_p99_ms < 30.0, "{r:?}");
    assert!(r.uplink_lq_pct > 95.0 && r.downlink_lq_pct > 95.0, "{r:?}");
    // OpenLRSng's failsafe delay is 1 s after the first missed packet.
    let fs = r.failsafe_ms.unwrap();
    assert!((1000.0..1100.0).contains(&fs), "{r:?}");
    assert!(r.recovery_ms.unwrap() < 1000.0, "{r:?}");
}

#[test]
fn fastest_profile_figures() {
    let s = scenario("--protocol openlrs39 --olrs-profile 4 --olrs-16ch --duration 12 --cut 6:8")
        .unwrap()
        .unwrap();
    let r = run(&s);
    assert!(r.bound && !r.failed(), "{r:?}");
    assert_eq!(
        (r.bit_rate_bps, r.interval_us, r.channels),
        (125_000, 7_000, 16)
    );
    assert!((135.0..=143.0).contains(&r.update_rate_hz), "{r:?}");
    assert!((3.0..7.0).contains(&r.latency_mean_ms), "{r:?}");
    assert!(r.uplink_lq_pct > 95.0 && r.downlink_lq_pct > 95.0, "{r:?}");
    let fs = r.failsafe_ms.unwrap();
    assert!((1000.0..1100.0).contains(&fs), "{r:?}");
    assert!(r.recovery_ms.unwrap() < 500.0, "{r:?}");
    assert!(r.to_json().contains("\"protocol\": \"openlrs39\""));
}

#[test]
fn taulink_only_options_are_refused() {
    for bad in [
        "--protocol openlrs38 --attack forge",
        "--protocol openlrs39 --phrase secret",
        "--protocol openlrs38 --rate F700",
        "--protocol openlrs38 --sweep",
        "--protocol openlrs38 --packet-level",
        "--olrs-16ch",
    ] {
        let e = scenario(bad).unwrap_err();
        assert!(e.contains("--"), "{bad}: {e}");
    }
    assert_eq!(scenario("").unwrap(), None);
}
