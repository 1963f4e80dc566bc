//! The estimator choice: the factory mode never leaves the complementary filter, the INS
//! takes over and hands back without an attitude jump, the indoor mode holds the vertical
//! on the baro, and the full INS follows GPS.

use ubx::{FixType, NavPvt};

use super::*;
use crate::estimation::GRAVITY_MPS2;
use crate::estimation::quaternion::{self, angle_between};

const DT: f32 = 0.001;

/// At rest, rolled `roll_deg` and pitched `pitch_deg`, with a small gyro offset.
fn resting(roll_deg: f32, pitch_deg: f32) -> ImuSample {
    let q = quaternion::from_euler(roll_deg.to_radians(), pitch_deg.to_radians(), 0.0);
    ImuSample {
        gyro_radps: [0.002, -0.001, 0.0005],
        accel_mps2: quaternion::ned_to_body_vector(q, [0.0, 0.0, -GRAVITY_MPS2]),
        mag: None,
    }
}

fn run(e: &mut Estimator, imu: &ImuSample, seconds: f32, altitude_m: f32) {
    for k in 0..(seconds / DT) as u32 {
        if k % 20 == 0 {
            e.baro(altitude_m);
        }
        e.update(imu, true, false, DT).unwrap();
    }
}

#[test]
fn the_factory_mode_stays_on_the_complementary_filter() {
    let mut e = Estimator::new(
        EstimatorMode::Complementary,
        complementary::Config::default(),
    );
    run(&mut e, &resting(10.0, 0.0), 5.0, 0.0);
    assert_eq!(e.source(), Source::Complementary);
    assert_eq!(e.vertical(), None);
}

#[test]
fn the_ins_takes_over_and_hands_back_without_an_attitude_jump() {
    // GIVEN the indoor INS on a frame resting at 10° roll, −5° pitch
    let mut e = Estimator::new(EstimatorMode::InsIndoor, complementary::Config::default());
    let imu = resting(10.0, -5.0);
    // WHEN the complementary filter has flown just short of the start time
    run(&mut e, &imu, INS_START_S - 0.01, 3.0);
    assert_eq!(e.source(), Source::Complementary);
    let before = e.attitude();
    // THEN the step on which the INS takes over moves the attitude no more than a gyro step
    let mut switched_at = None;
    let mut previous = before;
    for k in 0..20 {
        e.update(&imu, true, false, DT).unwrap();
        let jump = angle_between(previous, e.attitude()).to_degrees();
        assert!(jump < 0.01, "step {k}: {jump}° at the hand-over");
        previous = e.attitude();
        if e.source() == Source::Ins && switched_at.is_none() {
            switched_at = Some(k);
        }
    }
    assert!(switched_at.is_some(), "the INS never took over");
    // AND the INS levels on the same attitude (no slow jump either) after 20 s
    run(&mut e, &imu, 20.0, 3.0);
    let truth = quaternion::from_euler(10f32.to_radians(), -5f32.to_radians(), 0.0);
    let [r, p, _] = quaternion::to_euler(e.attitude());
    let [tr, tp, _] = quaternion::to_euler(truth);
    assert!(
        (r - tr).to_degrees().abs() < 0.3 && (p - tp).to_degrees().abs() < 0.3,
        "roll {} pitch {}",
        r.to_degrees(),
        p.to_degrees()
    );
    // WHEN the INS falls back (as on divergence) after flying, with the complementary
    // filter's own (stale) estimate elsewhere
    let _ = e.cf.reset(quaternion::from_euler(0.5, 0.5, 0.0), [0.0; 3]);
    let before = e.attitude();
    e.fall_back();
    // THEN the complementary filter continues from the INS's attitude
    assert_eq!(e.source(), Source::Complementary);
    assert_eq!(e.fallbacks(), 1);
    let jump = angle_between(before, e.attitude()).to_degrees();
    assert!(jump < 0.01, "{jump}° at the fallback");
    e.update(&imu, true, false, DT).unwrap();
    let jump = angle_between(before, e.attitude()).to_degrees();
    assert!(jump < 0.01, "{jump}° one step after the fallback");
    // AND the INS restarts from it later
    run(&mut e, &imu, INS_START_S + 0.1, 3.0);
    assert_eq!(e.source(), Source::Ins);
}

#[test]
fn the_indoor_ins_follows_the_baro_and_reports_the_climb() {
    let mut e = Estimator::new(EstimatorMode::InsIndoor, complementary::Config::default());
    let imu = resting(0.0, 0.0);
    run(&mut e, &imu, 5.0, 12.0);
    let (alt, climb) = e.vertical().expect("INS vertical with a baro");
    assert!((alt - 12.0).abs() < 0.1, "altitude {alt}");
    assert!(climb.abs() < 0.05, "climb {climb}");
    // A climb: 1 m/s² up for 1 s (the accelerometer feels it), then 1 m/s for 2 s.
    let (mut altitude, mut speed) = (12.0_f32, 0.0_f32);
    for k in 0..3000u32 {
        let up_accel = if k < 1000 { 1.0 } else { 0.0 };
        if k % 20 == 0 {
            e.baro(altitude);
        }
        let climbing = ImuSample {
            accel_mps2: [0.0, 0.0, -(GRAVITY_MPS2 + up_accel)],
            ..imu
        };
        e.update(&climbing, true, false, DT).unwrap();
        speed += up_accel * DT;
        altitude += speed * DT;
    }
    let (alt, climb) = e.vertical().unwrap();
    assert!((alt - altitude).abs() < 0.2, "altitude {alt} vs {altitude}");
    assert!((climb - 1.0).abs() < 0.1, "climb {climb}");
    // Without baro readings the vertical is not offered.
    for _ in 0..1000 {
        e.update(&imu, true, false, DT).unwrap();
    }
    assert_eq!(e.vertical(), None);
}

#[test]
fn the_full_ins_takes_the_gps_position() {
    let mut e = Estimator::new(EstimatorMode::Ins, complementary::Config::default());
    let imu = resting(0.0, 0.0);
    run(&mut e, &imu, 3.0, 0.0);
    assert_eq!(e.source(), Source::Ins);
    assert_eq!(e.horizontal(), None, "no fix yet");
    // A first fix sets home; the frame then sits 3 m north of it (the INS must move there,
    // through its rejection-reset logic if need be).
    let fix = |north_mm: i32| NavPvt {
        itow_ms: 0,
        fix_type: FixType::Fix3D,
        flags: 0x01,
        num_sv: 12,
        lon_e7: 80_000_000,
        // 1e-7° of latitude is 1.11 cm.
        lat_e7: 470_000_000 + north_mm * 9 / 100,
        height_mm: 0,
        h_msl_mm: 500_000,
        h_acc_mm: 800,
        v_acc_mm: 1500,
        vel_ned_mmps: [0; 3],
        g_speed_mmps: 0,
        head_mot_e5: 0,
        s_acc_mmps: 150,
        p_dop_e2: 120,
    };
    e.gps(&fix(0));
    for k in 0..20_000u32 {
        if k % 200 == 0 {
            e.gps(&fix(3_000));
        }
        if k % 20 == 0 {
            e.baro(0.0);
        }
        e.update(&imu, true, false, DT).unwrap();
    }
    let ([n, east], [vn, ve]) = e.horizontal().expect("position on a good fix");
    assert!((n - 3.0).abs() < 0.3 && east.abs() < 0.3, "{n} {east}");
    assert!(vn.abs() < 0.2 && ve.abs() < 0.2, "{vn} {ve}");
    assert!(e.home().is_some());
    // The fix lost: no horizontal position after the timeout.
    for _ in 0..1500 {
        e.update(&imu, true, false, DT).unwrap();
    }
    assert_eq!(e.horizontal(), None);
    assert_eq!(
        e.source(),
        Source::Ins,
        "the indoor pseudo-measurement keeps the INS"
    );
}

/// A still frame at `yaw_deg`, rolled 20° and pitched −10°, seeing the field of a place with
/// the given declination (the field's horizontal part points at magnetic north).
fn facing(yaw_deg: f32, declination_deg: f32, with_mag: bool) -> ImuSample {
    let q = quaternion::from_euler(0.35, -0.17, yaw_deg.to_radians());
    let d = declination_deg.to_radians();
    let field = [0.2 * d.cos(), 0.2 * d.sin(), 0.43];
    ImuSample {
        gyro_radps: [0.002, -0.001, 0.0005],
        accel_mps2: quaternion::ned_to_body_vector(q, [0.0, 0.0, -GRAVITY_MPS2]),
        mag: with_mag.then(|| quaternion::ned_to_body_vector(q, field)),
    }
}

#[test]
fn a_start_facing_anywhere_is_right_from_the_first_samples_and_the_ins_inherits_it() {
    for yaw_deg in [0.0_f32, 90.0, 180.0, -135.0] {
        // GIVEN the indoor INS on a frame powered up facing `yaw_deg`
        let mut e = Estimator::new(EstimatorMode::InsIndoor, complementary::Config::default());
        let imu = facing(yaw_deg, 0.0, true);
        let truth = quaternion::from_euler(0.35, -0.17, yaw_deg.to_radians());
        // WHEN it runs 10 ms, then past the INS start
        run(&mut e, &imu, 0.01, 0.0);
        let early = angle_between(e.attitude(), truth).to_degrees();
        run(&mut e, &imu, INS_START_S + 1.0, 0.0);
        // THEN the complementary filter started aligned and the INS took that over
        let late = angle_between(e.attitude(), truth).to_degrees();
        assert!(early < 0.5, "{yaw_deg}°: {early}° after 10 ms");
        assert_eq!(e.source(), Source::Ins);
        assert!(late < 0.5, "{yaw_deg}°: {late}° on the INS");
    }
}

#[test]
fn without_a_magnetometer_the_start_aligns_the_tilt_after_a_wait() {
    let mut e = Estimator::new(
        EstimatorMode::Complementary,
        complementary::Config::default(),
    );
    let imu = facing(0.0, 0.0, false);
    run(&mut e, &imu, ALIGN_WAIT_S + 0.01, 0.0);
    let [roll, pitch, _] = quaternion::to_euler(e.attitude());
    assert!(
        (roll - 0.35).abs() < 2e-3 && (pitch + 0.17).abs() < 2e-3,
        "{roll} {pitch}"
    );
}

#[test]
fn the_declination_setting_turns_magnetic_north_into_true_north() {
    // GIVEN 10° east declination in the settings and a frame facing magnetic north
    let mut settings = crate::settings::Settings::default();
    settings.set_text("mag.declination_deg", "10").unwrap();
    let Ok(setup) = crate::pipeline::from_settings(&settings) else {
        panic!("the settings make a setup");
    };
    let mut e = Estimator::new(
        EstimatorMode::Complementary,
        setup.loop_config.attitude_filter,
    );
    run(&mut e, &facing(10.0, 10.0, true), 3.0, 0.0);
    // THEN the heading is 10° (true)
    let [_, _, yaw] = quaternion::to_euler(e.attitude());
    assert!(
        (yaw.to_degrees() - 10.0).abs() < 0.5,
        "{}",
        yaw.to_degrees()
    );
}
