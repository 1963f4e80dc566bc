//! `taulink-sim --attack`: a third radio in the chip-level medium attacks the keyed link for
//! 30 s of virtual time. Acceptance is counted at the victims' link cores (a core's count of
//! valid frames rising on a packet the medium delivered from the attacker), never assumed.
//! Each run must see nothing accepted, no rebind, no wrong output, and keep the LQ figures
//! quoted in spec §12.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use taulink_sim::scenario::Scenario;
use taulink_sim::{Cli, Report, run};

use clap::Parser;

fn scenario(args: &str) -> Scenario {
    let cli =
        Cli::try_parse_from(std::iter::once("taulink-sim").chain(args.split_whitespace())).unwrap();
    let s: Scenario = cli.scenario();
    assert!(s.key.is_some() && s.chip_level && s.attack.is_some());
    s
}

fn attacked(args: &str) -> Report {
    let r = run(&scenario(args), |_| {});
    println!("{args}: {}", r.to_json());
    r
}

#[test]
fn forged_frames_are_never_accepted_and_the_link_flies_on() {
    let r = attacked("--attack forge --phrase amber-kettle-forge");
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
    // A 53-byte key-agreement offer (28 ms at the bind rate, 19.2 kbps) every 20 ms.
    assert!(r.attacker_frames_sent > 600, "{r:?}");
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

/// Issue 30, finding 3, at chip level in every rate mode: a radio near the module records
/// the flight side's nonce frames, the flight side is power-cycled (a session to replay
/// from), then in every wrap the radio jams a downlink slot at the module and replays a
/// recorded nonce frame in the next one named by it. The master refuses every one (its
/// epoch is live), so the link flies on as in the same run with the radio silent.
#[test]
fn replayed_nonce_frames_never_take_a_live_link_in_any_rate_mode() {
    for rate in ["L50", "M100", "F250", "F500", "F700"] {
        let s = scenario(&format!("--attack nonce-replay --rate {rate}"));
        let clean = run(
            &Scenario {
                silent_attacker: true,
                ..s.clone()
            },
            |_| {},
        );
        let r = run(&s, |_| {});
        println!("{rate}: {}", r.to_json());
        println!("{rate} clean: {}", clean.to_json());
        assert_eq!(r.attacker_frames_accepted, 0, "{rate}");
        // Every replay reached the master verified (the radio is near it) and was refused;
        // the jams went out in between.
        assert!(r.nonce_frames_refused >= 8, "{rate}: {r:?}");
        assert!(
            r.attacker_frames_sent >= 2 * u64::from(r.nonce_frames_refused) - 2,
            "{rate}: {r:?}"
        );
        // One epoch per flight boot, none forced.
        assert_eq!((r.power_cycles, r.handshakes_adopted), (1, 2), "{rate}");
        assert!(
            r.update_rate_hz >= 0.95 * clean.update_rate_hz,
            "{rate}: {} vs {} clean",
            r.update_rate_hz,
            clean.update_rate_hz
        );
        // The only failsafe is the flight side's power-off, as in the clean run.
        assert_eq!((r.failsafes, clean.failsafes), (1, 1), "{rate}");
        assert!(
            (r.failsafe_at_s - clean.failsafe_at_s).abs() < 0.05,
            "{rate}"
        );
        assert_eq!((r.resyncs, r.errors), (0, 0), "{rate}");
    }
}

/// Issue 30, finding 1, at chip level: a passive radio records the bind on a phrase and
/// 1 024 slots of the link (the nonce frames among them); a dictionary that holds the true
/// phrase finds no check that tells it from the other words.
#[test]
fn a_recording_of_the_bind_and_the_link_checks_no_phrase_offline() {
    let r = attacked("--attack guess");
    let g = r.guess.expect("the guesser's figures");
    assert!(r.bound_s > 0.0, "the flight side bound over the air");
    assert_eq!(r.attacker_frames_sent, 0, "passive");
    assert!(g.bind_frames >= 3, "offer, accept, confirmation: {g:?}");
    assert!(g.link_frames > 500 && g.nonce_frames >= 2, "{g:?}");
    assert_eq!((g.verdict.guesses, g.verdict.checks), (11, 4));
    assert!(!g.verdict.offline_checkable);
    assert!(r.to_json().contains("\"offline_checkable\": false"));
    assert!(!r.failed());
}
