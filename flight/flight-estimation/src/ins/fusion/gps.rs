//! GPS position and velocity: direct observations of the NED position and velocity states
//! (H rows are unit vectors, DERIVATION.md §4).

use super::Fusion;
use crate::ins::{Filter, index};
use crate::{Error, check_finite};

impl Filter {
    /// Fuses a GPS position (NED, m, relative to the origin). With `vertical` false only
    /// north and east are used (the vertical comes from the barometer, as in the reference).
    ///
    /// # Errors
    /// [`Error::NonFinite`] for non-finite input, [`Error::Diverged`] if the update failed.
    pub fn fuse_gps_position(
        &mut self,
        position_ned_m: [f32; 3],
        vertical: bool,
    ) -> Result<Fusion, Error> {
        let cfg = self.config;
        let var = [cfg.gps_horizontal_var_m2, cfg.gps_vertical_var_m2];
        self.fuse_gps_position_with_variance(position_ned_m, vertical, var)
    }

    /// As [`Filter::fuse_gps_position`], with the measurement's own variances
    /// `[horizontal, vertical]` (m²) instead of the configured ones — the receiver's
    /// reported accuracy, as the Tau Labs firmware rescaled them at each fix.
    ///
    /// # Errors
    /// As [`Filter::fuse_gps_position`]; also [`Error::NonFinite`] for a non-finite variance.
    pub fn fuse_gps_position_with_variance(
        &mut self,
        position_ned_m: [f32; 3],
        vertical: bool,
        var_m2: [f32; 2],
    ) -> Result<Fusion, Error> {
        check_finite(&position_ned_m)?;
        check_finite(&var_m2)?;
        let [h, v] = var_m2;
        let rows = [
            (index::POSITION, h, true),
            (index::POSITION + 1, h, true),
            (index::POSITION + 2, v, vertical),
        ];
        self.fuse_direct_rows(&rows, &position_ned_m)
    }

    /// Fuses a GPS velocity (NED, m/s), all three axes.
    ///
    /// # Errors
    /// As [`Filter::fuse_gps_position`].
    pub fn fuse_gps_velocity(&mut self, velocity_ned_mps: [f32; 3]) -> Result<Fusion, Error> {
        let r = self.config.gps_velocity_var_m2ps2;
        self.fuse_gps_velocity_with_variance(velocity_ned_mps, r)
    }

    /// As [`Filter::fuse_gps_velocity`] with the measurement's own variance per axis.
    ///
    /// # Errors
    /// As [`Filter::fuse_gps_position`].
    pub fn fuse_gps_velocity_with_variance(
        &mut self,
        velocity_ned_mps: [f32; 3],
        r: f32,
    ) -> Result<Fusion, Error> {
        check_finite(&velocity_ned_mps)?;
        check_finite(&[r])?;
        let rows = [
            (index::VELOCITY, r, true),
            (index::VELOCITY + 1, r, true),
            (index::VELOCITY + 2, r, true),
        ];
        self.fuse_direct_rows(&rows, &velocity_ned_mps)
    }

    /// Gates all enabled rows against the prior first; only if every row passes are they
    /// fused one after the other (PX4 rejects a GPS sample as a whole, too). The first two
    /// rows are always enabled, the third as its flag says (the GPS height).
    fn fuse_direct_rows(
        &mut self,
        rows: &[(usize, f32, bool); 3],
        measured: &[f32; 3],
    ) -> Result<Fusion, Error> {
        let worst = rows
            .iter()
            .zip(measured.iter())
            .filter(|((_, _, used), _)| *used)
            .map(|(&(k, r, _), &z)| self.direct_test(k, z, r))
            .fold(0.0_f32, |a, b| if b > a || b.is_nan() { b } else { a });
        let outcome = Fusion::from_ratio(worst);
        if outcome.is_fused() {
            let [(k0, r0, _), (k1, r1, _), (k2, r2, vertical)] = *rows;
            let [z0, z1, z2] = *measured;
            if vertical {
                self.fuse_direct([(k0, r0), (k1, r1), (k2, r2)], [z0, z1, z2]);
            } else {
                self.fuse_direct([(k0, r0), (k1, r1)], [z0, z1]);
            }
            self.finish_update()?;
        }
        Ok(outcome)
    }
}
