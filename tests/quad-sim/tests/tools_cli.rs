//! The `lqg` and `sysid` binaries as a user meets them: `--help` exits 0 and explains the
//! options, a misspelt flag or sub-command is refused with a suggestion (exit 2), nonsense
//! values are refused with the reason (issue 14), and short runs print the documented JSON.

#![allow(clippy::unwrap_used)] // test helpers

use std::process::{Command, Output};

fn run(bin: &str, args: &[&str]) -> Output {
    Command::new(bin).args(args).output().unwrap()
}

fn lqg(args: &[&str]) -> Output {
    run(env!("CARGO_BIN_EXE_lqg"), args)
}

fn sysid(args: &[&str]) -> Output {
    run(env!("CARGO_BIN_EXE_sysid"), args)
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

const FRAME: [&str; 4] = ["--ln-beta1", "10", "--tau", "0.03"];

#[test]
fn help_describes_the_options_and_exits_0() {
    for (out, needles) in [
        (lqg(&["--help"]), &["gains", "step", "Examples:"][..]),
        (
            lqg(&["step", "--help"]),
            &[
                "--ln-beta1 <L>",
                "Motor time constant",
                "--duration <S>",
                "`--seconds` is the same flag",
                "--plot <DIR>",
                "--plot-format",
            ][..],
        ),
        (
            lqg(&["gains", "--help"]),
            &["--q <ANGLE,RATE,TORQUE>", "--kf-r <R>"][..],
        ),
        (
            sysid(&["--help"]),
            &[
                "--ln-beta1 <L>",
                "--gyro-noise",
                "--seed",
                "--quiet",
                "Examples:",
            ][..],
        ),
    ] {
        assert!(out.status.success());
        let help = text(&out.stdout);
        for n in needles {
            assert!(help.contains(n), "help lacks {n:?}:\n{help}");
        }
    }
    assert!(text(&lqg(&["--version"]).stdout).starts_with("lqg 0."));
    assert!(text(&sysid(&["--version"]).stdout).starts_with("sysid 0."));
}

#[test]
fn misspellings_are_refused_with_a_suggestion() {
    let out = lqg(&["stpe"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("a similar subcommand exists: 'step'"));
    let mut args = vec!["step", "--stpe", "5"];
    args.extend(FRAME);
    let out = lqg(&args);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("a similar argument exists: '--step'"));
    let out = sysid(&["--ln-beta1", "10", "--tau", "0.03", "--gyro-nosie", "1"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("'--gyro-noise'"));
}

#[test]
fn nonsense_is_refused_with_the_reason() {
    for (extra, says) in [
        (&["--seconds", "-5"][..], "must be within 0..=3600, got -5"),
        (&["--seconds", "1e9"], "got 1e9"),
        (&["--duration", "0"], "greater than 0"),
        (&["--step", "nan"], "nan is not a finite number"),
        (&["--tau", "0"], "--tau"),
        (&["--q", "4,0.04"], "needs 3 comma-separated numbers"),
        (&["--mode", "angle"], "possible values: rate, attitude"),
    ] {
        let mut args = vec!["step"];
        args.extend(FRAME);
        args.extend(extra);
        // A later --tau overrides FRAME's; clap refuses a repeated flag, so drop FRAME's.
        if extra.first() == Some(&"--tau") {
            args.drain(3..5);
        }
        let out = lqg(&args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?} accepted: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    let out = sysid(&["--ln-beta1", "10", "--tau", "0.03", "--duration", "nan"]);
    assert_eq!(out.status.code(), Some(2));
    let out = sysid(&["--tau", "0.03"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("--ln-beta1 <L>"));
}

#[test]
fn short_runs_print_the_documented_json() {
    let out = lqg(&["gains", "--ln-beta1", "10", "--tau", "0.03"]);
    assert!(out.status.success());
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["lqr_rate_gain"].as_array().unwrap().len(), 2);
    assert_eq!(j["costs_source"], "autotuned");

    let mut args = vec![
        "step",
        "--duration",
        "0.3",
        "--step",
        "-50",
        "--compare-pid",
    ];
    args.extend(FRAME);
    let out = lqg(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["step"], -50.0);
    assert!(j["lqg"]["rise_time_s"].as_f64().unwrap() > 0.0);
    assert!(j["pid"]["overshoot_pct"].is_number());

    let out = sysid(&[
        "--ln-beta1",
        "10",
        "--tau",
        "0.03",
        "--duration",
        "2",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(out.stderr.is_empty());
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["experiment"]["seconds"], 2.0);
    assert_eq!(j["identified"]["ln_beta"].as_array().unwrap().len(), 3);
}

#[test]
fn step_plot_is_written_in_the_chosen_format() {
    let dir = std::env::temp_dir().join(format!("lqg-plot-{}", std::process::id()));
    let d = dir.to_str().unwrap();
    let mut args = vec![
        "step",
        "--duration",
        "0.2",
        "--plot",
        d,
        "--plot-format",
        "svg",
    ];
    args.extend(FRAME);
    let out = lqg(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let svg = std::fs::read_to_string(dir.join("step.svg")).unwrap();
    for label in [
        "response (deg/s)",
        "time (s)",
        "LQG",
        "setpoint",
        "Controller output",
    ] {
        assert!(svg.contains(label), "{label} missing");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn oneshot_answers_help_and_refuses_misspellings() {
    let oneshot = |args: &[&str]| run(env!("CARGO_BIN_EXE_oneshot"), args);
    let out = oneshot(&["--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    for n in ["--runs <N>", "--esc-filter <N>", "--json", "--plot <DIR>"] {
        assert!(help.contains(n), "help lacks {n:?}:\n{help}");
    }
    let out = oneshot(&["--runz", "3"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("a similar argument exists: '--runs'"));
    let out = oneshot(&["--runs", "1"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "one run per condition has no spread"
    );
}
