//! Heading-only magnetometer fusion (DERIVATION.md §4). The reading is rotated into the
//! level heading frame with the filter's roll and pitch, its horizontal part is scaled to
//! the earth field's horizontal magnitude (only its direction carries heading), and it is
//! compared with the earth field rotated by yaw. The H rows therefore only touch the yaw
//! direction of q to first order. The reference's row 8 (H = 0, K = 0) is not computed.

use super::Fusion;
use crate::estimation::ins::equations::{heading_field, level_frame_field};
use crate::estimation::ins::{Filter, STATES, covariance, index};
use crate::estimation::math::inv_sqrt;
use crate::estimation::{Error, check_finite};

impl Filter {
    /// The horizontal heading-frame field measured by `mag_body`, scaled to the earth field's
    /// horizontal magnitude. `None` when either horizontal magnitude is ~0.
    pub(crate) fn heading_measurement(&self, mag_body: [f32; 3]) -> Option<[f32; 2]> {
        let [z0, z1, _] = level_frame_field(self.attitude(), mag_body);
        let [b0, b1, _] = self.config.earth_field_ned;
        let measured2 = z0 * z0 + z1 * z1;
        let earth2 = b0 * b0 + b1 * b1;
        if !(measured2 > 1e-12 && earth2 > 1e-12) {
            return None;
        }
        let scale = earth2 * inv_sqrt(earth2) * inv_sqrt(measured2);
        Some([z0 * scale, z1 * scale])
    }

    /// Fuses a magnetometer reading (body FRD, the unit of `earth_field_ned`).
    ///
    /// # Errors
    /// [`Error::NonFinite`] for non-finite input, [`Error::Diverged`] if the update failed.
    pub fn fuse_mag(&mut self, mag_body: [f32; 3]) -> Result<Fusion, Error> {
        check_finite(&mag_body)?;
        let Some(z) = self.heading_measurement(mag_body) else {
            return Ok(Fusion::Rejected {
                test_ratio: f32::INFINITY,
            });
        };
        let r = self.config.mag_var;
        let worst = self.mag_rows(z, r, false);
        let outcome = Fusion::from_ratio(worst);
        if outcome.is_fused() {
            self.mag_rows(z, r, true);
            self.finish_update()?;
        }
        Ok(outcome)
    }

    /// Runs both heading rows: returns the larger test ratio, and fuses them when `apply`.
    /// Y and H are re-linearised before the second row (cheap, no trig).
    fn mag_rows(&mut self, z: [f32; 2], r: f32, apply: bool) -> f32 {
        let mut worst = 0.0_f32;
        for (row, &measured) in z.iter().enumerate() {
            let [b0, b1, _] = self.config.earth_field_ned;
            let (y, h) = heading_field(self.attitude(), [b0, b1]);
            let (Some(&predicted), Some(h_row)) = (y.get(row), h.get(row)) else {
                continue;
            };
            let ph = self.p_h(h_row);
            let s = ph
                .iter()
                .skip(index::QUATERNION)
                .zip(h_row.iter())
                .map(|(a, b)| a * b)
                .sum::<f32>()
                + r;
            let innovation = measured - predicted;
            let ratio = self.test_ratio(innovation, s);
            worst = if ratio > worst || ratio.is_nan() {
                ratio
            } else {
                worst
            };
            if apply {
                self.apply_update(&ph, s, innovation);
            }
        }
        worst
    }

    /// P·hᵀ for an H row that is non-zero only on the quaternion.
    fn p_h(&self, h: &[f32; 4]) -> [f32; STATES] {
        let mut ph = [0.0; STATES];
        for (m, &h_m) in h.iter().enumerate() {
            let col = covariance::column(&self.p, index::QUATERNION + m);
            for (acc, c) in ph.iter_mut().zip(col.iter()) {
                *acc += h_m * c;
            }
        }
        ph
    }
}
