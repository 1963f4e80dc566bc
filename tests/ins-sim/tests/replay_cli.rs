//! The `replay` binary as a user meets it: `--help` exits 0 and explains the options, a
//! misspelt flag is refused with a suggestion, and nonsense (issue 14) is refused with a
//! clear error and a non-zero exit: an empty file, time going backwards, a 1e30 gyro
//! reading, NaN values, `--declination-deg nan`. A small valid log replays and plots.

#![allow(clippy::unwrap_used, clippy::panic)] // test helpers

use std::path::PathBuf;
use std::process::{Command, Output};

fn replay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_replay"))
        .args(args)
        .output()
        .unwrap()
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A scratch directory of this test process.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("replay-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Two seconds at rest: 250 Hz IMU, 50 Hz mag, 10 Hz baro, 5 Hz GPS.
fn valid_log() -> String {
    let mut s = String::new();
    for k in 0..500u64 {
        let t = 4000 + k * 4000;
        if k % 5 == 0 {
            s.push_str(&format!("{t},mag,0.2,0.0,0.43\n"));
        }
        s.push_str(&format!("{t},imu,0.0,0.0,-9.81,0.0,0.0,0.0\n"));
        if k % 25 == 0 {
            s.push_str(&format!("{t},baro,100.0\n"));
        }
        if k % 50 == 0 {
            s.push_str(&format!("{t},gps,100000,85000000,470000000,0.0,0.0,0.0\n"));
        }
    }
    s
}

fn run_on(name: &str, log: &str, extra: &[&str]) -> Output {
    let d = scratch(name);
    let input = d.join("sensors.csv");
    std::fs::write(&input, log).unwrap();
    let out = d.join("est.csv");
    let mut args = vec![
        input.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend(extra);
    let o = replay(&args);
    let _ = std::fs::remove_dir_all(d);
    o
}

#[test]
fn help_describes_the_options_and_exits_0() {
    let out = replay(&["--help"]);
    assert!(out.status.success());
    let help = text(&out.stdout);
    for n in [
        "<SENSORS.csv|FLIGHT.ulg>",
        "--out <EST.csv>",
        "--truth <TRUTH.csv>",
        "--declination-deg <DEG>",
        "Magnetic declination",
        "--plot <DIR>",
        "--plot-format",
        "Examples:",
    ] {
        assert!(help.contains(n), "help lacks {n:?}:\n{help}");
    }
    assert!(text(&replay(&["--version"]).stdout).starts_with("replay 0."));
}

#[test]
fn misspelt_flag_is_refused_with_a_suggestion() {
    let out = replay(&["x.csv", "--out", "y.csv", "--truht", "z.csv"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("a similar argument exists: '--truth'"));
}

#[test]
fn nonsense_is_refused_with_the_reason() {
    let log = valid_log();
    let backwards = log.replacen("8000,imu", "1000,imu", 1);
    let absurd = log.replacen(
        "8000,imu,0.0,0.0,-9.81,0.0,0.0,0.0",
        "8000,imu,0.0,0.0,-9.81,1e30,0.0,0.0",
        1,
    );
    let nan = log.replacen(
        "8000,imu,0.0,0.0,-9.81,0.0",
        "8000,imu,0.0,0.0,-9.81,nan",
        1,
    );
    let far_south = log.replacen("470000000", "-950000000", 1);
    for (name, log, says) in [
        ("empty", "", "no IMU records"),
        ("blank", "\n\n", "no IMU records"),
        (
            "backwards",
            backwards.as_str(),
            "time goes backwards: 1000 µs after 4000 µs",
        ),
        (
            "absurd",
            absurd.as_str(),
            "rate 1e30 rad/s is beyond ±100 rad/s",
        ),
        ("nan", nan.as_str(), "not a finite number: \"nan\""),
        (
            "latitude",
            far_south.as_str(),
            "latitude -95 deg is outside -90..=90 deg",
        ),
    ] {
        let out = run_on(name, log, &[]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name} accepted: {err}");
        assert!(err.contains(says), "{name}: {err}");
    }
    for bad in ["nan", "inf", "400", "east"] {
        let out = run_on("decl", &log, &["--declination-deg", bad]);
        let err = text(&out.stderr);
        assert_eq!(
            out.status.code(),
            Some(2),
            "--declination-deg {bad} accepted"
        );
        assert!(err.contains("--declination-deg"), "{err}");
    }
    let out = replay(&["/nonexistent/sensors.csv", "--out", "/tmp/x.csv"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("/nonexistent/sensors.csv"));
}

#[test]
fn valid_log_replays_and_plots_svg() {
    let d = scratch("plot");
    let plots = d.join("figs");
    let out = run_on(
        "valid",
        &valid_log(),
        &[
            "--declination-deg",
            "-3.5",
            "--plot",
            plots.to_str().unwrap(),
            "--plot-format",
            "svg",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        out.stderr.is_empty(),
        "--quiet printed {}",
        text(&out.stderr)
    );
    let svg = std::fs::read_to_string(plots.join("attitude.svg")).unwrap();
    for label in ["roll (deg)", "yaw (deg)", "time (s)", "estimate"] {
        assert!(svg.contains(label), "{label} missing");
    }
    for f in ["velocity.svg", "position.svg", "bias.svg"] {
        assert!(plots.join(f).exists(), "{f} missing");
    }
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_cut_flight_log_is_refused_with_its_offset() {
    let d = scratch("ulog");
    let log = d.join("cut.ulg");
    // ULog's magic and version, then a header cut short.
    std::fs::write(&log, b"ULog\x01\x12\x35\x01\x00\x00").unwrap();
    let out = replay(&[
        log.to_str().unwrap(),
        "--out",
        d.join("e.csv").to_str().unwrap(),
    ]);
    let _ = std::fs::remove_dir_all(&d);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("cut.ulg: "),
        "{}",
        text(&out.stderr)
    );
}
