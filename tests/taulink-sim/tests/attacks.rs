//! `taulink-sim --attack`: a third radio in the chip-level medium attacks the keyed link for
//! 30 s of virtual time. Acceptance is counted at the victims' link cores (a core's count of
//! valid frames rising on a packet the medium delivered from the attacker), never assumed.
//! Each run must see nothing accepted, no rebind, no wrong output, and keep the LQ figures
//! quoted in spec §12.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use taulink_sim::scenario::Scenario;
use taulink_sim::{Cli, Report, run};

use clap::Parser;

fn attacked(args: &str) -> Report {
    let cli =
        Cli::try_parse_from(std::iter::once("taulink-sim").chain(args.split_whitespace())).unwrap();
    let s: Scenario = cli.scenario();
    assert!(s.key.is_some() && s.chip_level && s.attack.is_some());
    let r = run(&s, |_| {});
    println!("{args}: {}", r.to_json());
    r
}

#[test]
fn forged_frames_are_never_accepted_and_the_link_flies_on() {
    let r = attacked("--attack forge --phrase forge-test");
    assert_eq!(r.attack.as_deref(), Some("forge"));
    assert!(r.attacker_frames_sent > 5_000, "{r:?}");
    assert_eq!(r.attacker_frames_accepted, 0);
    // Forgeries reach the link code (the chip's header and CRC pass them) and are rejected.
    assert!(r.link_rejected > 100, "{r:?}");
    assert_eq!(r.errors, 0, "an output that was not the handset's");
    assert_eq!((r.failsafes, r.resyncs), (0, 0));
    // The forger's frames collide with some of the link's: LQ about 90 %.
    assert!(
        r.uplink_lq_mean > 85.0 && r.downlink_lq_mean > 85.0,
        "{r:?}"
    );
}

#[test]
fn replayed_frames_are_never_accepted_across_flight_restarts() {
    let r = attacked("--attack replay");
    assert!(r.attacker_frames_sent > 500, "{r:?}");
    assert_eq!(r.attacker_frames_accepted, 0);
    assert!(
        r.link_rejected > 100,
        "replays reached the link code: {r:?}"
    );
    assert_eq!(r.power_cycles, 2);
    // One failsafe per power cycle (the flight side was off), none from the replays.
    assert_eq!(r.failsafes, 2, "{r:?}");
    assert_eq!(r.errors, 0);
    assert!(
        r.uplink_lq_mean > 85.0 && r.downlink_lq_mean > 80.0,
        "{r:?}"
    );
}

#[test]
fn spoofed_binds_never_rebind_a_power_cycled_flight_side() {
    let r = attacked("--attack bind-spoof");
    assert!(r.attacker_frames_sent > 900, "{r:?}");
    assert_eq!(r.attacker_frames_accepted, 0);
    assert_eq!(r.power_cycles, 5);
    assert_eq!(
        r.rebinds, 0,
        "the flight side ran another link after a boot"
    );
    assert_eq!(r.failsafes, 5, "{r:?}");
    assert_eq!(r.errors, 0);
    assert!(r.uplink_lq_mean > 90.0, "{r:?}");
}
