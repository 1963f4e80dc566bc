//! The `flight-sitl` binary as a user meets it: `--help` exits 0 and lists the scenarios and
//! options, a misspelt flag or scenario is refused with a suggestion (exit 2), nonsense
//! values and refused settings exit 2 with the reason before anything flies.

#![allow(clippy::unwrap_used)]

use std::process::{Command, Output};

fn sitl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_flight-sitl"))
        .args(args)
        .output()
        .unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn help_lists_scenarios_and_options() {
    let out = sitl(&["--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    for n in [
        "link-cut",
        "imu-stall",
        "settings-corrupt",
        "oneshot-experiment",
        "--rate <RATE>",
        "--module-set <NAME=VALUE>",
        "--json",
        "Examples:",
    ] {
        assert!(help.contains(n), "help lacks {n:?}:\n{help}");
    }
    let out = sitl(&["oneshot-experiment", "--help"]);
    assert!(out.status.success());
    assert!(text(&out.stdout).contains("--runs <N>"));
}

#[test]
fn misspellings_and_nonsense_exit_2_with_the_reason() {
    let out = sitl(&["link-cut", "--altitud", "30"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("'--altitude'"),
        "{}",
        text(&out.stderr)
    );
    let out = sitl(&["link-cutt"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("link-cut"),
        "{}",
        text(&out.stderr)
    );
    for args in [
        &["link-cut", "--altitude", "nan"][..],
        &["hover", "--duration", "-5"],
        &["hover", "--set", "output.protocol=pwm"],
        &["hover", "--set", "no.such=1"],
    ] {
        let out = sitl(args);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            text(&out.stderr)
        );
        assert!(!text(&out.stderr).is_empty());
    }
}
