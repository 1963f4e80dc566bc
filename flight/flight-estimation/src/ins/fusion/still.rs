//! The indoor pseudo-measurement (Tau Labs' indoor mode): without GPS, nothing observes the
//! horizontal velocity, so an error in the estimated tilt — gravity leaking into the
//! horizontal — would integrate into a velocity nobody corrects. Telling the filter that the
//! frame does not move horizontally, with a generous variance, makes the tilt observable
//! from the accelerometer again, through the velocity states, the way GPS velocity does.

use super::Fusion;
use crate::ins::{Filter, index};
use crate::{Error, check_finite};

impl Filter {
    /// Fuses "north and east velocity are zero" with variance `var_m2ps2` ((m/s)²). Not
    /// gated: a constraint is not a sensor that can be an outlier, and a gate would lock
    /// out the very correction a drifted tilt needs (once the velocity estimate is wrong by
    /// more than the gate, every later pseudo-measurement would be refused). The variance
    /// says how fast the frame may really move; it bounds the tilt error the pseudo-measurement
    /// can induce while the frame does move.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite variance, [`Error::Diverged`] if the update
    /// failed.
    pub fn fuse_zero_horizontal_velocity(&mut self, var_m2ps2: f32) -> Result<Fusion, Error> {
        check_finite(&[var_m2ps2])?;
        let worst = [index::VELOCITY, index::VELOCITY + 1]
            .iter()
            .map(|&k| self.direct_test(k, 0.0, var_m2ps2))
            .fold(0.0_f32, |a, b| if b > a || b.is_nan() { b } else { a });
        self.fuse_direct(
            [
                (index::VELOCITY, var_m2ps2),
                (index::VELOCITY + 1, var_m2ps2),
            ],
            [0.0; 2],
        );
        self.finish_update()?;
        Ok(Fusion::Fused { test_ratio: worst })
    }
}

#[cfg(test)]
mod tests {
    use crate::ins::{Config, Filter};
    use crate::quaternion;

    #[test]
    fn holds_the_horizontal_velocity_and_levels_a_wrong_tilt() {
        // GIVEN a filter at rest whose attitude is wrong by 5° of roll
        let mut f = Filter::new(Config::default());
        f.reset_attitude(
            quaternion::from_euler(5f32.to_radians(), 0.0, 0.0),
            1e-2,
            1e-2,
        );
        let accel = [0.0, 0.0, -crate::GRAVITY_MPS2];
        // WHEN it predicts at 1 kHz with the pseudo-measurement at 10 Hz for 60 s
        for k in 0..60_000 {
            f.predict([0.0; 3], accel, 0.001).unwrap();
            if k % 100 == 0 {
                f.fuse_zero_horizontal_velocity(0.25).unwrap();
            }
        }
        // THEN the tilt is corrected and the velocity stays near zero
        let s = f.state();
        let [roll, pitch, _] = quaternion::to_euler(s.attitude);
        assert!(roll.to_degrees().abs() < 0.5, "roll {}", roll.to_degrees());
        assert!(
            pitch.to_degrees().abs() < 0.5,
            "pitch {}",
            pitch.to_degrees()
        );
        let [vn, ve, _] = s.velocity_ned_mps;
        assert!(vn.abs() < 0.05 && ve.abs() < 0.05, "{vn} {ve}");
    }

    #[test]
    fn refuses_a_non_finite_variance() {
        let mut f = Filter::new(Config::default());
        assert!(f.fuse_zero_horizontal_velocity(f32::NAN).is_err());
    }
}
