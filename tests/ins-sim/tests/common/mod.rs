//! Shared harness of the scenario tests: run a scenario through a default INS and collect
//! the final errors, the worst errors after a settling time and bias convergence times.
#![allow(dead_code, clippy::indexing_slicing)] // test harness (clippy.toml allows this in tests)

use flight_app::estimation::ins::aiding::AidingConfig;
use flight_app::estimation::ins::{Config, Ins, State};
use ins_sim::metrics::{Errors, errors};
use ins_sim::scenario::{Scenario, Simulation};
use ins_sim::trajectory::Truth;

/// Result of one run.
pub struct Run {
    pub ins: Ins,
    pub state: State,
    pub truth: Truth,
    pub last: Errors,
    /// Worst |error| per quantity over the steps after `check_from_s`.
    pub worst: Errors,
    /// Time after which the attitude error stayed below 1°.
    pub attitude_below_1deg_s: Option<f64>,
    /// Time after which every gyro-bias axis stayed within 10 % of the true bias.
    pub gyro_bias_t10_s: Option<f64>,
    /// Time after which the z accel bias stayed within 10 % of the true bias.
    pub accel_bias_t10_s: Option<f64>,
    pub rejections: u32,
    pub resets: u32,
}

pub fn new_ins() -> Ins {
    Ins::new(Config::default(), AidingConfig::default())
}

fn worst_of(w: &mut Errors, e: &Errors) {
    w.attitude_deg = w.attitude_deg.max(e.attitude_deg.abs());
    w.roll_deg = w.roll_deg.max(e.roll_deg.abs());
    w.pitch_deg = w.pitch_deg.max(e.pitch_deg.abs());
    w.yaw_deg = w.yaw_deg.max(e.yaw_deg.abs());
    for i in 0..3 {
        w.position_m[i] = w.position_m[i].max(e.position_m[i].abs());
        w.velocity_mps[i] = w.velocity_mps[i].max(e.velocity_mps[i].abs());
    }
}

/// Runs `scenario` for `seconds` after `setup` prepared the INS.
pub fn run(
    scenario: Scenario,
    seconds: f64,
    check_from_s: f64,
    setup: impl FnOnce(&mut Ins),
) -> Run {
    let mut ins = new_ins();
    setup(&mut ins);
    run_with(ins, scenario, seconds, check_from_s)
}

/// Runs `scenario` for `seconds` with a prepared INS.
pub fn run_with(mut ins: Ins, scenario: Scenario, seconds: f64, check_from_s: f64) -> Run {
    let mut sim = Simulation::new(scenario);
    let mut worst = Errors::default();
    let mut last = Errors::default();
    let mut truth = Simulation::new(scenario).next_sample().truth;
    let (mut att_ok_since, mut gb_ok_since, mut ab_ok_since) = (Some(0.0), Some(0.0), Some(0.0));
    let (mut rejections, mut resets) = (0, 0);
    for _ in 0..sim.steps_in(seconds) {
        let sample = sim.next_sample();
        let out = sim.drive(&mut ins, &sample);
        for o in [out.mag, out.baro, out.gps_position, out.gps_velocity]
            .into_iter()
            .flatten()
        {
            match o {
                flight_app::estimation::ins::Aided::Fused(_) => {}
                flight_app::estimation::ins::Aided::Rejected { .. } => rejections += 1,
                flight_app::estimation::ins::Aided::Reset(_) => resets += 1,
            }
        }
        truth = sample.truth;
        let t = truth.time_s;
        let state = ins.state();
        last = errors(&state, &truth);
        if t >= check_from_s {
            worst_of(&mut worst, &last);
        }
        if last.attitude_deg >= 1.0 {
            att_ok_since = None;
        } else if att_ok_since.is_none() {
            att_ok_since = Some(t);
        }
        let gb = scenario.imu.gyro_bias.at(t);
        // As the reference harness: within 10 % of the largest true bias component.
        let gb_scale = gb.iter().fold(1e-3_f64, |a, b| a.max(b.abs()));
        let gb_ok =
            (0..3).all(|i| (f64::from(state.gyro_bias_radps[i]) - gb[i]).abs() <= 0.1 * gb_scale);
        if !gb_ok {
            gb_ok_since = None;
        } else if gb_ok_since.is_none() {
            gb_ok_since = Some(t);
        }
        let ab = scenario.imu.accel_bias.at(t)[2];
        let ab_ok = (f64::from(state.accel_bias_z_mps2) - ab).abs() <= 0.1 * ab.abs().max(1e-2);
        if !ab_ok {
            ab_ok_since = None;
        } else if ab_ok_since.is_none() {
            ab_ok_since = Some(t);
        }
    }
    let state = ins.state();
    Run {
        ins,
        state,
        truth,
        last,
        worst,
        attitude_below_1deg_s: att_ok_since,
        gyro_bias_t10_s: gb_ok_since,
        accel_bias_t10_s: ab_ok_since,
        rejections,
        resets,
    }
}

/// Prints a one-line summary (visible with `--nocapture`).
pub fn report(name: &str, r: &Run) {
    println!(
        "{name}: att {:.4}° yaw {:.4}° pos {:.4} m vel {:.4} m/s | worst att {:.4}° tilt {:.4}° pos {:.4} vel {:.4} | bg {:?} ab_z {:.4} | att<1° {:?} bg_t10 {:?} baz_t10 {:?} | rej {} resets {}",
        r.last.attitude_deg,
        r.last.yaw_deg,
        r.last.position_max_m(),
        r.last.velocity_max_mps(),
        r.worst.attitude_deg,
        r.worst.tilt_deg(),
        r.worst.position_max_m(),
        r.worst.velocity_max_mps(),
        r.state.gyro_bias_radps,
        r.state.accel_bias_z_mps2,
        r.attitude_below_1deg_s,
        r.gyro_bias_t10_s,
        r.accel_bias_t10_s,
        r.rejections,
        r.resets,
    );
}

/// The static "assertState" of the reference (flight-core's `DERIVATION.md` §7), used with tighter
/// numbers: pos and vel < `pos_vel`, roll/pitch < `tilt_deg`, wrap-safe yaw < `yaw_deg`, gyro bias
/// within
/// `bias` of the truth and z accel bias within `bias` of the truth.
pub fn assert_state(
    r: &Run,
    pos_vel: f64,
    tilt_deg: f64,
    yaw_deg: f64,
    bias: f64,
    gyro_bias: [f64; 3],
    accel_bias_z: f64,
) {
    let e = &r.last;
    assert!(
        e.position_max_m() < pos_vel,
        "position error {:?}",
        e.position_m
    );
    assert!(
        e.velocity_max_mps() < pos_vel,
        "velocity error {:?}",
        e.velocity_mps
    );
    assert!(
        e.tilt_deg() < tilt_deg,
        "roll/pitch error {} {}",
        e.roll_deg,
        e.pitch_deg
    );
    assert!(e.yaw_deg.abs() < yaw_deg, "yaw error {}", e.yaw_deg);
    for i in 0..3 {
        let b = f64::from(r.state.gyro_bias_radps[i]);
        assert!(
            (b - gyro_bias[i]).abs() < bias,
            "gyro bias {i}: {b} vs {}",
            gyro_bias[i]
        );
    }
    let ab_z = f64::from(r.state.accel_bias_z_mps2);
    assert!(
        (ab_z - accel_bias_z).abs() < bias,
        "z accel bias {ab_z} vs {accel_bias_z}"
    );
}
