//! The attitude from one still sample, whatever way the frame points: roll and pitch from
//! the accelerometer (gravity), heading from the magnetometer levelled with that roll and
//! pitch (tilt compensated) against the earth field's horizontal direction, which the
//! magnetic declination turns from magnetic to true north. Both estimators start from it
//! (`Complementary::align`, `ins::Filter::align`) instead of level and north, and re-align
//! their heading from it when the magnetometer keeps disagreeing (cold path: libm).

use crate::ins::equations::level_frame_field;
use crate::quaternion::{self, Quaternion};

/// (roll, pitch) from a specific-force vector that is pure gravity (level reads [0, 0, −g]).
#[must_use]
pub fn tilt_from_accel(accel_mps2: [f32; 3]) -> [f32; 2] {
    let [ax, ay, az] = accel_mps2;
    [
        libm::atan2f(-ay, -az),
        libm::atan2f(ax, libm::sqrtf(ay * ay + az * az)),
    ]
}

/// Heading (rad, from true north towards east) that makes the magnetometer reading
/// `mag_body` agree with `earth_field_ned` at the given roll and pitch:
/// ψ = atan2(Be_e, Be_n) − atan2(z₁, z₀), z the reading in the level heading frame.
/// `None` when either horizontal part is ~0 (a field along the vertical says nothing).
#[must_use]
pub fn heading_from_mag(
    roll_rad: f32,
    pitch_rad: f32,
    mag_body: [f32; 3],
    earth_field_ned: [f32; 3],
) -> Option<f32> {
    let level = quaternion::from_euler(roll_rad, pitch_rad, 0.0);
    let [z0, z1, _] = level_frame_field(level, mag_body);
    let [b0, b1, _] = earth_field_ned;
    if z0 * z0 + z1 * z1 < 1e-12 || b0 * b0 + b1 * b1 < 1e-12 {
        return None;
    }
    Some(libm::atan2f(b1, b0) - libm::atan2f(z1, z0))
}

/// The attitude of a still frame from one accelerometer sample and, if there is one, a
/// magnetometer sample (heading north without it).
#[must_use]
pub fn attitude(
    accel_mps2: [f32; 3],
    mag_body: Option<[f32; 3]>,
    earth_field_ned: [f32; 3],
) -> Quaternion {
    let [roll, pitch] = tilt_from_accel(accel_mps2);
    let yaw = mag_body
        .and_then(|m| heading_from_mag(roll, pitch, m, earth_field_ned))
        .unwrap_or(0.0);
    quaternion::from_euler(roll, pitch, yaw)
}

/// The horizontal earth-field direction for a magnetic declination (rad, east positive):
/// magnetic north turned from true north. Only its direction matters to the heading.
#[must_use]
pub fn field_for_declination(declination_rad: f32) -> [f32; 3] {
    let (sin, cos) = crate::math::sin_cos(declination_rad);
    [cos, sin, 0.0]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::GRAVITY_MPS2;

    #[test]
    fn any_heading_and_tilt_is_found_from_one_sample() {
        // GIVEN a still frame at every heading 15° apart, tilted up to 60°, in a field
        // dipping 70° with a declination of 12° east
        let field = [20.0 * libm::cosf(0.21), 20.0 * libm::sinf(0.21), 55.0_f32];
        for k in 0..24 {
            for (roll, pitch) in [(0.0, 0.0), (0.3, -0.2), (-0.5, 0.4), (1.0, 0.3)] {
                let yaw = (15.0 * k as f32).to_radians() - core::f32::consts::PI;
                let truth = quaternion::from_euler(roll, pitch, yaw);
                let accel = quaternion::ned_to_body_vector(truth, [0.0, 0.0, -GRAVITY_MPS2]);
                let mag = quaternion::ned_to_body_vector(truth, field);
                // WHEN aligned from that one sample
                let q = attitude(accel, Some(mag), field);
                // THEN the attitude is the truth
                let err = quaternion::angle_between(q, truth).to_degrees();
                assert!(err < 0.01, "yaw {yaw} roll {roll} pitch {pitch}: {err}°");
            }
        }
    }

    #[test]
    fn the_declination_turns_magnetic_into_true_north() {
        // A level frame whose nose points at magnetic north, 10° east of true north.
        let d = 10f32.to_radians();
        let field = field_for_declination(d);
        let heading = heading_from_mag(0.0, 0.0, [1.0, 0.0, 2.0], field).unwrap();
        assert!((heading - d).abs() < 1e-6, "{heading}");
        // Without a magnetometer: level, north.
        let q = attitude([0.0, 0.0, -GRAVITY_MPS2], None, field);
        assert!(quaternion::angle_between(q, quaternion::IDENTITY) < 1e-6);
        assert_eq!(heading_from_mag(0.0, 0.0, [0.0, 0.0, 1.0], field), None);
    }
}
