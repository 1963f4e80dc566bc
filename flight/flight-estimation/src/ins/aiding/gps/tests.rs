//! GPS aiding: units and frame of the measurement, fix loss and regain, and latency
//! compensation measured against an uncompensated run.

use ubx::{FixType, NavPvt};

use super::*;
use crate::ins::aiding::AidingConfig;
use crate::ins::{Config, Ins};

const HOME: Home = Home {
    lat_e7: 522_227_387,
    lon_e7: -748_276,
    h_msl_mm: 83_104,
};

fn pvt(north_m: f64, east_m: f64, up_m: f64, vel_mps: [f64; 3]) -> NavPvt {
    let to_rad = core::f64::consts::PI / 180.0 * 1e-7;
    let lat0 = f64::from(HOME.lat_e7) * to_rad;
    let dlat = north_m / EARTH_RADIUS_M / to_rad;
    let dlon = east_m / (EARTH_RADIUS_M * lat0.cos()) / to_rad;
    NavPvt {
        itow_ms: 0,
        fix_type: FixType::Fix3D,
        flags: 0x01,
        num_sv: 12,
        lon_e7: HOME.lon_e7 + dlon.round() as i32,
        lat_e7: HOME.lat_e7 + dlat.round() as i32,
        height_mm: 0,
        h_msl_mm: HOME.h_msl_mm + (up_m * 1e3).round() as i32,
        h_acc_mm: 800,
        v_acc_mm: 1500,
        vel_ned_mmps: vel_mps.map(|v| (v * 1e3).round() as i32),
        g_speed_mmps: 0,
        head_mot_e5: 0,
        s_acc_mmps: 150,
        p_dop_e2: 120,
    }
}

#[test]
fn measurement_is_ned_from_home_with_the_receivers_accuracy() {
    let mut a = GpsAiding::new(GpsAidingConfig::default());
    assert_eq!(
        a.measurement(&pvt(0.0, 0.0, 0.0, [0.0; 3])),
        None,
        "no home yet"
    );
    a.set_home(HOME);
    let m = a
        .measurement(&pvt(100.0, -50.0, 3.0, [1.0, -2.0, 0.5]))
        .unwrap();
    let [n, e, d] = m.position_ned_m;
    assert!((n - 100.0).abs() < 0.02, "{n}");
    assert!((e + 50.0).abs() < 0.02, "{e}");
    assert!((d + 3.0).abs() < 1e-3, "{d}");
    assert_eq!(m.velocity_ned_mps, [1.0, -2.0, 0.5]);
    assert!((m.horizontal_var_m2 - 0.64).abs() < 1e-6);
    assert!((m.vertical_var_m2 - 2.25).abs() < 1e-6);
    assert!((m.velocity_var_m2ps2 - 0.0225).abs() < 1e-6);
    // A receiver claiming millimetres gets the floor.
    let mut p = pvt(0.0, 0.0, 0.0, [0.0; 3]);
    p.h_acc_mm = 1;
    p.s_acc_mmps = 1;
    let m = a.measurement(&p).unwrap();
    assert!((m.horizontal_var_m2 - 0.09).abs() < 1e-6);
    assert!((m.velocity_var_m2ps2 - 0.01).abs() < 1e-6);
}

#[test]
fn fix_loss_is_not_fused_and_regain_fuses_again() {
    let mut ins = Ins::new(Config::default(), AidingConfig::default());
    let mut gps = GpsAiding::new(GpsAidingConfig::default());
    let first = gps
        .fuse(&mut ins, &pvt(0.0, 0.0, 0.0, [0.0; 3]), 0)
        .unwrap();
    assert!(matches!(first, GpsUpdate::Fused { .. }));
    assert_eq!(gps.home(), Some(Home { ..HOME }));
    assert!(gps.has_fix());

    let before = ins.state();
    for (fix_type, flags, sats, h_acc) in [
        (FixType::NoFix, 0, 0, 99_000),
        (FixType::Fix2D, 1, 5, 8000),
        (FixType::Fix3D, 0, 8, 3000), // 3-D but not gnssFixOK
        (FixType::Fix3D, 1, 4, 1000),
        (FixType::Fix3D, 1, 9, 9000),
    ] {
        let mut p = pvt(50.0, 50.0, 0.0, [5.0, 0.0, 0.0]);
        (p.fix_type, p.flags, p.num_sv, p.h_acc_mm) = (fix_type, flags, sats, h_acc);
        let out = gps.fuse(&mut ins, &p, 100_000).unwrap();
        assert!(
            matches!(out, GpsUpdate::Unusable(_)),
            "{fix_type:?}: {out:?}"
        );
        assert!(!gps.has_fix());
        assert_eq!(ins.state(), before, "a lost fix must not move the estimate");
    }

    let out = gps
        .fuse(&mut ins, &pvt(1.0, 0.0, 0.0, [0.0; 3]), 200_000)
        .unwrap();
    assert!(matches!(out, GpsUpdate::Fused { .. }), "{out:?}");
    assert!(gps.has_fix());
    assert!(
        ins.state().position_ned_m[0] > 0.1,
        "regained fix pulls the estimate"
    );
    // Home stays where the first fix put it.
    assert_eq!(gps.home(), Some(HOME));
}

/// Accelerates north at 1 m/s² from rest for 12 s with a perfect IMU; GPS at 10 Hz
/// describes the vehicle 200 ms before it arrives. Returns the final position and
/// velocity errors (m, m/s).
fn run_with_latency(latency_us: u32) -> (f32, f32) {
    const ACCEL: f64 = 1.0;
    const GPS_LATENCY_S: f64 = 0.2;
    let dt = 0.002;
    let mut ins = Ins::new(Config::default(), AidingConfig::default());
    let mut gps = GpsAiding::new(GpsAidingConfig {
        latency_us,
        ..GpsAidingConfig::default()
    });
    gps.set_home(HOME);
    let g = crate::GRAVITY_MPS2;
    let steps = 6000;
    for k in 1..=steps {
        let t = f64::from(k) * dt;
        ins.predict([0.0; 3], [ACCEL as f32, 0.0, -g], dt as f32)
            .unwrap();
        let now_us = (t * 1e6).round() as u64;
        gps.record(now_us, &ins.state());
        if k % 50 == 0 {
            let tf = (t - GPS_LATENCY_S).max(0.0);
            let p = pvt(0.5 * ACCEL * tf * tf, 0.0, 0.0, [ACCEL * tf, 0.0, 0.0]);
            gps.fuse(&mut ins, &p, now_us).unwrap();
        }
    }
    let t = f64::from(steps) * dt;
    let s = ins.state();
    let pos_err = s.position_ned_m[0] - (0.5 * ACCEL * t * t) as f32;
    let vel_err = s.velocity_ned_mps[0] - (ACCEL * t) as f32;
    (pos_err.abs(), vel_err.abs())
}

#[test]
fn latency_compensation_gives_a_smaller_error_than_none() {
    let (pos_none, vel_none) = run_with_latency(0);
    let (pos_comp, vel_comp) = run_with_latency(200_000);
    println!(
        "uncompensated: {pos_none:.3} m {vel_none:.3} m/s; compensated: {pos_comp:.3} m {vel_comp:.3} m/s"
    );
    // Uncompensated, the estimate is pulled towards where the vehicle was 200 ms ago
    // (2.4 m behind at 12 m/s).
    assert!(pos_none > 0.5, "{pos_none}");
    assert!(pos_comp < 0.25 * pos_none, "{pos_comp} vs {pos_none}");
    assert!(vel_comp < 0.5 * vel_none + 0.02, "{vel_comp} vs {vel_none}");
    assert!(pos_comp < 0.2 && vel_comp < 0.05, "{pos_comp} {vel_comp}");
}
