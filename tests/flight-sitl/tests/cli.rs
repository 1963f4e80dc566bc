//! The `flight-sitl` binary as a user meets it: `--help` exits 0 and lists the scenarios and
//! options, a misspelt flag or scenario is refused with a suggestion (exit 2), nonsense
//! values and refused settings exit 2 with the reason before anything flies.

use cli_test::Run;

fn sitl(args: &[&str]) -> Run {
    cli_test::run(env!("CARGO_BIN_EXE_flight-sitl"), args)
}

#[test]
fn help_lists_scenarios_and_options() {
    sitl(&["--help"]).assert_lists(&[
        "link-cut",
        "imu-stall",
        "settings-corrupt",
        "oneshot-experiment",
        "--rate <RATE>",
        "--module-set <NAME=VALUE>",
        "--json",
        "Examples:",
    ]);
    sitl(&["oneshot-experiment", "--help"]).assert_lists(&["--runs <N>"]);
}

#[test]
fn misspellings_and_nonsense_exit_2_with_the_reason() {
    sitl(&["link-cut", "--altitud", "30"]).assert_refused("'--altitude'");
    sitl(&["link-cutt"]).assert_refused("link-cut");
    for args in [
        &["link-cut", "--altitude", "nan"][..],
        &["hover", "--duration", "-5"],
        &["hover", "--set", "output.protocol=pwm"],
        &["hover", "--set", "no.such=1"],
    ] {
        let out = sitl(args);
        assert_eq!(out.code, Some(2), "{args:?}: {}", out.stderr);
        assert!(!out.stderr.is_empty());
    }
}
