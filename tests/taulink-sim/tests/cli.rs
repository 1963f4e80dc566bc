//! The `taulink-sim` binary as a user meets it: `--help` and `--version` exit 0 and explain
//! the options, a misspelt flag is refused with a suggestion, nonsense values are refused
//! with a message naming the flag, and a short run prints the JSON the README describes.

#![allow(clippy::unwrap_used)] // test helpers

use std::process::{Command, Output};

fn sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_taulink-sim"))
        .args(args)
        .output()
        .unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn help_describes_every_option_and_exits_0() {
    let out = sim(&["--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    for needle in [
        "--rate",
        "Rate mode: L50",
        "--loss <P>",
        "probability",
        "--duration <S>",
        "Virtual duration, seconds",
        "--seed",
        "--json",
        "--sweep",
        "--quiet",
        "Examples:",
        "Exit status",
    ] {
        assert!(help.contains(needle), "--help lacks {needle:?}:\n{help}");
    }
    let v = sim(&["--version"]);
    assert!(v.status.success());
    assert!(text(&v.stdout).starts_with("taulink-sim 0."));
}

#[test]
fn misspelt_flag_is_refused_with_a_suggestion() {
    let out = sim(&["--durration", "5"]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(err.contains("unexpected argument '--durration'"), "{err}");
    assert!(err.contains("--duration"), "no suggestion: {err}");
}

#[test]
fn nonsense_values_are_refused_with_the_reason() {
    for (args, says) in [
        (&["--loss", "2"][..], "within 0..=1"),
        (&["--duration", "-5"], "--duration"),
        (&["--duration", "nan"], "within 0..=86400"),
        (&["--duration", "0"], "greater than 0"),
        (&["--distance", "nan"], "the distance (m)"),
        (&["--ratio", "3"], "power of two"),
        (&["--cut", "5:2"], "end after it starts"),
        (&["--rate", "F1000"], "possible values"),
    ] {
        let out = sim(args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?} accepted: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
}

#[test]
fn short_run_prints_the_documented_json() {
    let out = sim(&["--duration", "0.5", "--packet-level", "--no-bind", "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json = text(&out.stdout);
    // Quiet on stderr: no status line with --json.
    assert!(out.stderr.is_empty(), "{}", text(&out.stderr));
    for field in [
        "\"rate\": \"F250\"",
        "\"duration_s\": 0.500",
        "\"update_rate_hz\"",
        "\"latency_p99_ms\"",
        "\"errors\": 0",
    ] {
        assert!(json.contains(field), "{field} missing: {json}");
    }
}

#[test]
fn plot_draws_the_link_figure_and_refuses_a_sweep() {
    let dir = std::env::temp_dir().join(format!("taulink-sim-plot-{}", std::process::id()));
    let d = dir.to_str().unwrap();
    let out = sim(&[
        "--duration",
        "3",
        "--cut",
        "1:2",
        "--packet-level",
        "--no-bind",
        "--quiet",
        "--plot",
        d,
        "--plot-format",
        "svg",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let svg = std::fs::read_to_string(dir.join("link.svg")).unwrap();
    for label in [
        "LQ (%)",
        "RSSI (dBm)",
        "updates (1/s)",
        "latency (ms)",
        "path cut",
        "virtual time (s)",
    ] {
        assert!(svg.contains(label), "{label} missing");
    }
    let _ = std::fs::remove_dir_all(&dir);
    let out = sim(&["--sweep", "--plot", d]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("cannot be used with"),
        "{}",
        text(&out.stderr)
    );
}
