//! The `taulink-sim` binary as a user meets it: `--help` and `--version` exit 0 and explain
//! the options, a misspelt flag is refused with a suggestion, nonsense values are refused
//! with a message naming the flag, and a short run prints the JSON the README describes.

#![allow(clippy::unwrap_used)] // test helpers

use cli_test::Run;

fn sim(args: &[&str]) -> Run {
    cli_test::run(env!("CARGO_BIN_EXE_taulink-sim"), args)
}

#[test]
fn help_describes_every_option_and_exits_0() {
    sim(&["--help"]).assert_lists(&[
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
    ]);
    let v = sim(&["--version"]);
    assert!(v.success());
    assert!(v.stdout.starts_with("taulink-sim 0."));
}

#[test]
fn misspelt_flag_is_refused_with_a_suggestion() {
    let out = sim(&["--durration", "5"]);
    out.assert_refused("unexpected argument '--durration'");
    assert!(
        out.stderr.contains("--duration"),
        "no suggestion: {}",
        out.stderr
    );
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
        (&["--rate", "F1000"], "L50, M100, F250, F500 or F700"),
        (
            &["--dynamic-power", "--walk", "500:100"],
            "go away from the module",
        ),
        (&["--dynamic-power", "--walk", "0:100"], "FROM (m)"),
        (&["--walk"], "--dynamic-power"),
        (&["--dynamic-power"], "--walk"),
        (
            &["--dynamic-power", "--walk", "--sweep"],
            "cannot be used with",
        ),
    ] {
        sim(args).assert_refused(says);
    }
}

#[test]
fn short_run_prints_the_documented_json() {
    let out = sim(&["--duration", "0.5", "--packet-level", "--no-bind", "--json"]);
    out.assert_lists(&[
        "\"rate\": \"F250\"",
        "\"duration_s\": 0.500",
        "\"update_rate_hz\"",
        "\"latency_p99_ms\"",
        "\"errors\": 0",
    ]);
    // Quiet on stderr: no status line with --json.
    assert!(out.stderr.is_empty(), "{}", out.stderr);
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
    assert!(out.success(), "{}", out.stderr);
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
    sim(&["--sweep", "--plot", d]).assert_refused("cannot be used with");
}

#[test]
fn openlrs_runs_print_json_and_refuse_taulink_options() {
    let out = sim(&["--protocol", "openlrs39", "--duration", "3", "--json"]);
    out.assert_lists(&[
        "\"protocol\": \"openlrs39\"",
        "\"bound\": true",
        "\"update_rate_hz\"",
        "\"errors\": 0",
    ]);
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    for (args, says) in [
        (
            &["--protocol", "openlrs38", "--attack", "forge"][..],
            "--attack has no meaning",
        ),
        (&["--protocol", "openlrs38", "--phrase", "x"], "--phrase"),
        (&["--protocol", "openlrs39", "--rate", "F700"], "--rate"),
    ] {
        sim(args).assert_refused(says);
    }
}

#[test]
fn a_dynamic_power_walk_prints_both_runs_as_json() {
    let out = sim(&[
        "--dynamic-power",
        "--walk",
        "2000:20000",
        "--duration",
        "2",
        "--json",
    ]);
    assert!(out.success(), "{}", out.stderr);
    for field in [
        "\"plan\"",
        "\"rate\": \"F250\"",
        "\"fixed\"",
        "\"dynamic\": {",
        "\"module_mw\"",
        "\"downlink_lq\"",
    ] {
        assert!(out.stdout.contains(field), "{field} in {}", out.stdout);
    }
}
