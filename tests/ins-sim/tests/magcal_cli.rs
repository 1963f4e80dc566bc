//! The `magcal` tool end to end: a synthetic rotation with known hard and soft iron is
//! recovered; a one-axis rotation and a short file are refused with a reason.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::needless_range_loop
)] // test code

use std::process::Command;

const OFFSET: [f64; 3] = [12.0, -30.0, 45.0];
const SOFT: [[f64; 3]; 3] = [[1.15, 0.05, 0.0], [0.05, 0.92, -0.04], [0.0, -0.04, 1.02]];

/// `n` readings (µT) of a 50 µT field turned through the given directions, with 0.15 µT
/// noise.
fn csv(dirs: impl Iterator<Item = [f64; 3]>) -> String {
    let mut s = String::from("time_us,mx,my,mz\n");
    let mut state = 0x2545_F491_4F6C_DD1D_u64;
    let mut noise = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.15 * 12f64.sqrt()
    };
    for (i, d) in dirs.enumerate() {
        let b = d.map(|v| 50.0 * v);
        let raw: Vec<f64> = (0..3)
            .map(|r| (0..3).map(|c| SOFT[r][c] * b[c]).sum::<f64>() + OFFSET[r] + noise())
            .collect();
        s.push_str(&format!(
            "{},{:.3},{:.3},{:.3}\n",
            i * 20_000,
            raw[0],
            raw[1],
            raw[2]
        ));
    }
    s
}

fn sphere(n: usize) -> impl Iterator<Item = [f64; 3]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n).map(move |i| {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let a = golden * i as f64;
        [r * a.cos(), r * a.sin(), z]
    })
}

fn run(name: &str, content: &str, json: bool) -> std::process::Output {
    let dir = std::env::temp_dir().join(format!("magcal-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, content).unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_magcal"));
    cmd.arg(&path);
    if json {
        cmd.arg("--json");
    }
    cmd.output().unwrap()
}

fn number_after(text: &str, key: &str) -> f64 {
    let at = text.find(key).unwrap() + key.len();
    text[at..]
        .trim_start_matches([':', '['])
        .split([',', ']', '}'])
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

#[test]
fn recovers_a_known_calibration_as_json() {
    let out = run("good.csv", &csv(sphere(500)), true);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = String::from_utf8(out.stdout).unwrap();
    assert!(json.contains("\"matrix\":[["), "{json}");
    let residual = number_after(&json, "\"residual_pct\"");
    assert!(residual < 1.0, "{json}");
    let ox = number_after(&json, "\"offset\"");
    assert!((ox - OFFSET[0]).abs() < 0.3, "{json}");
    let field = number_after(&json, "\"field\"");
    // det(SOFT) ≈ 1.07: the field keeps the soft iron's mean scale.
    assert!((field - 50.0).abs() < 3.0, "{json}");
}

#[test]
fn text_output_names_every_figure() {
    let out = run("text.csv", &csv(sphere(300)), false);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for key in ["offset", "matrix", "field", "residual_pct"] {
        assert!(text.contains(key), "{key} missing in {text}");
    }
}

#[test]
fn refuses_a_single_plane_rotation_with_a_reason() {
    let yaw_only = (0..300).map(|i| {
        let psi = i as f64 * 0.04;
        [0.45 * psi.cos(), 0.45 * psi.sin(), 0.89]
    });
    let out = run("plane.csv", &csv(yaw_only), true);
    assert!(!out.status.success());
    assert!(out.stdout.is_empty());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("single plane"), "{err}");
}

#[test]
fn refuses_too_few_samples_and_a_wrong_header() {
    let out = run("short.csv", &csv(sphere(30)), false);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("too few samples"));
    let out = run("header.csv", "t,x,y,z\n0,1,2,3\n", false);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("header"));
}

#[test]
fn magcal_answers_help_and_refuses_misspellings() {
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_magcal"))
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&["--help"]);
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(help.contains("--json"), "{help}");
    let out = run(&["mag.csv", "--jsno"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("'--json'"));
}
