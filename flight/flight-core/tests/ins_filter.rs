//! Properties of the 14-state filter itself: input refusal, gating outcomes, covariance
//! symmetry and positive definiteness, independent instances.

#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::needless_range_loop
)] // test code

use flight_core::estimation::Error;
use flight_core::estimation::ins::{Config, Filter, Fusion};

const G: f32 = 9.805;

/// Cholesky in f64: true when the matrix is positive definite.
fn is_positive_definite(p: &[[f32; 14]; 14]) -> bool {
    let mut l = [[0.0_f64; 14]; 14];
    for i in 0..14 {
        for j in 0..=i {
            let mut s = f64::from(p[i][j]);
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if s <= 0.0 {
                    return false;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    true
}

fn assert_symmetric_pd(f: &Filter) {
    let p = f.covariance();
    for i in 0..14 {
        for j in 0..14 {
            assert_eq!(
                p[i][j].to_bits(),
                p[j][i].to_bits(),
                "P[{i}][{j}] != P[{j}][{i}]"
            );
        }
    }
    assert!(is_positive_definite(p), "P is not positive definite");
}

#[test]
fn covariance_stays_symmetric_positive_definite() {
    // GIVEN a filter cycled through predicts and every kind of correction while rotating
    let mut f = Filter::new(Config::default());
    for k in 0..20_000 {
        f.predict([0.01, -0.02, 0.3], [0.1, 0.2, -G], 0.002)
            .unwrap();
        if k % 50 == 0 {
            f.fuse_gps_position([0.0, 0.0, 0.0], true).unwrap();
            f.fuse_gps_velocity([0.0; 3]).unwrap();
        }
        if k % 10 == 3 {
            f.fuse_baro(0.0).unwrap();
        }
        if k % 10 == 7 {
            f.fuse_mag([400.0, 0.0, 1600.0]).unwrap();
        }
        // THEN P is exactly symmetric and positive definite throughout
        if k % 1000 == 0 {
            assert_symmetric_pd(&f);
        }
    }
    assert_symmetric_pd(&f);
}

#[test]
fn non_finite_inputs_are_refused_without_change() {
    let mut f = Filter::new(Config::default());
    let before = *f.state_vector();
    assert_eq!(
        f.predict([f32::NAN, 0.0, 0.0], [0.0, 0.0, -G], 0.002),
        Err(Error::NonFinite)
    );
    assert_eq!(
        f.predict([0.0; 3], [0.0, f32::INFINITY, -G], 0.002),
        Err(Error::NonFinite)
    );
    assert_eq!(
        f.predict([0.0; 3], [0.0, 0.0, -G], 0.0),
        Err(Error::InvalidTimeStep)
    );
    assert_eq!(
        f.predict([0.0; 3], [0.0, 0.0, -G], f32::NAN),
        Err(Error::InvalidTimeStep)
    );
    assert_eq!(
        f.fuse_gps_position([f32::NAN, 0.0, 0.0], false),
        Err(Error::NonFinite)
    );
    assert_eq!(
        f.fuse_gps_velocity([0.0, f32::NEG_INFINITY, 0.0]),
        Err(Error::NonFinite)
    );
    assert_eq!(f.fuse_baro(f32::NAN), Err(Error::NonFinite));
    assert_eq!(f.fuse_mag([0.0, 0.0, f32::NAN]), Err(Error::NonFinite));
    assert_eq!(*f.state_vector(), before);
}

#[test]
fn an_outlier_is_rejected_as_an_outcome() {
    // GIVEN a settled filter at the origin
    let mut f = Filter::new(Config::default());
    for _ in 0..100 {
        f.predict([0.0; 3], [0.0, 0.0, -G], 0.002).unwrap();
        f.fuse_gps_velocity([0.0; 3]).unwrap();
        f.fuse_gps_position([0.0; 3], false).unwrap();
    }
    let before = *f.state_vector();
    // WHEN GPS claims the craft jumped 50 m north
    let outcome = f.fuse_gps_position([50.0, 0.0, 0.0], false).unwrap();
    // THEN it is rejected with a test ratio far above 1 and nothing changes
    match outcome {
        Fusion::Rejected { test_ratio } => assert!(test_ratio > 100.0, "{test_ratio}"),
        Fusion::Fused { .. } => panic!("outlier fused"),
    }
    assert_eq!(*f.state_vector(), before);
    // AND a consistent fix is fused with a small ratio
    match f.fuse_gps_position([0.01, 0.0, 0.0], false).unwrap() {
        Fusion::Fused { test_ratio } => assert!(test_ratio < 0.05, "{test_ratio}"),
        Fusion::Rejected { .. } => panic!("good fix rejected"),
    }
}

#[test]
fn instances_are_independent() {
    // GIVEN two filters, only one of which sees a position fix
    let mut a = Filter::new(Config::default());
    let b = Filter::new(Config::default());
    a.fuse_gps_position([3.0, 4.0, 0.0], false).unwrap();
    // THEN the other is untouched
    assert!(a.state().position_ned_m[0] > 2.9);
    assert_eq!(b.state().position_ned_m, [0.0; 3]);
}

#[test]
fn mag_only_moves_heading() {
    // GIVEN a level filter facing north and a reading 2° to the east of north, tilted
    // by a vertical component that disagrees with the earth field
    let mut f = Filter::new(Config::default());
    let yaw = 2f32.to_radians();
    let reading = [400.0 * yaw.cos(), -400.0 * yaw.sin(), 900.0];
    let before = f.state();
    let outcome = f.fuse_mag(reading).unwrap();
    assert!(outcome.is_fused());
    let after = f.state();
    let [r0, p0, _] = flight_core::estimation::quaternion::to_euler(before.attitude);
    let [r1, p1, y1] = flight_core::estimation::quaternion::to_euler(after.attitude);
    // THEN yaw moved towards +2° while roll and pitch did not move at all
    assert!(y1 > 0.0, "yaw {y1}");
    assert!(
        (r1 - r0).abs() < 1e-6 && (p1 - p0).abs() < 1e-6,
        "roll {r1} pitch {p1}"
    );
}

#[test]
fn sensor_noise_figures_set_the_noise_terms_and_keep_the_rest() {
    use flight_core::estimation::ins::SensorNoise;
    let base = Config::default();
    let told = base.with_sensor_noise(
        &SensorNoise {
            gyro_radps: Some(1e-3),
            accel_mps2: Some(0.05),
            gps_velocity_mps: Some(0.2),
            ..SensorNoise::default()
        },
        0.002,
    );
    // PSD = σ²·dt for the IMU, variance = σ² for the measurements.
    assert!((told.gyro_noise_psd[2] - 2e-9).abs() < 1e-15);
    assert!((told.accel_noise_psd - 5e-6).abs() < 1e-12);
    assert!((told.gps_velocity_var_m2ps2 - 0.04).abs() < 1e-7);
    // Figures not given keep the tuning.
    assert_eq!(told.mag_var, base.mag_var);
    assert_eq!(told.baro_var_m2, base.baro_var_m2);
    assert_eq!(told.gps_horizontal_var_m2, base.gps_horizontal_var_m2);
    assert_eq!(told.gyro_bias_walk_psd, base.gyro_bias_walk_psd);
}

#[test]
fn gyro_bias_walk_slows_once_settled_and_reopens_after_a_reset() {
    use flight_core::estimation::ins::Ins;
    use flight_core::estimation::ins::aiding::{Aided, AidingConfig};
    let aiding = AidingConfig::default().for_known_noise();
    let fast = Config::default().gyro_bias_walk_psd;
    let slow = AidingConfig::KNOWN_NOISE_SETTLED_GYRO_BIAS_WALK_PSD;
    let mut ins = Ins::new(Config::default(), aiding);
    let level = [0.0, 0.0, -G];
    for _ in 0..(9.9 / 0.002) as usize {
        ins.predict([0.0; 3], level, 0.002).unwrap();
    }
    assert_eq!(ins.filter().config().gyro_bias_walk_psd, fast);
    for _ in 0..100 {
        ins.predict([0.0; 3], level, 0.002).unwrap();
    }
    assert_eq!(ins.filter().config().gyro_bias_walk_psd, slow);
    // Facing south while the filter believes north: rejections until a yaw reset, which
    // re-opens the bias and brings the fast walk back.
    let mut reset = false;
    for _ in 0..100 {
        ins.predict([0.0; 3], level, 0.002).unwrap();
        if let Aided::Reset(_) = ins.mag([-400.0, 0.0, 1600.0]).unwrap() {
            reset = true;
            break;
        }
    }
    assert!(reset);
    assert_eq!(ins.filter().config().gyro_bias_walk_psd, fast);
    // The default policy never slows down.
    let mut ins = Ins::new(Config::default(), AidingConfig::default());
    for _ in 0..(20.0 / 0.002) as usize {
        ins.predict([0.0; 3], level, 0.002).unwrap();
    }
    assert_eq!(ins.filter().config().gyro_bias_walk_psd, fast);
}
