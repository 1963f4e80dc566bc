//! Heading-only magnetometer fusion (DERIVATION.md §4). The reading is rotated into the
//! level heading frame with the filter's roll and pitch, its horizontal part is scaled to
//! the earth field's horizontal magnitude (only its direction carries heading), and it is
//! compared with the earth field rotated by yaw. The H rows therefore only touch the yaw
//! direction of q to first order. The reference's row 8 (H = 0, K = 0) is not computed.

use super::Fusion;
use crate::ins::equations::{heading_field, level_frame_field};
use crate::ins::{Filter, STATES, covariance, index};
use crate::math::inv_sqrt;
use crate::{Error, check_finite};

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
        let [b0, b1, _] = self.config.earth_field_ned;
        let ([y0, y1], [h0, h1]) = heading_field(self.attitude(), [b0, b1]);
        let [z0, z1] = z;
        // Both rows gated against the prior.
        let ph0 = self.p_h(&h0);
        let ph1 = self.p_h(&h1);
        let ratio0 = self.test_ratio(z0 - y0, quaternion_dot(&ph0, &h0) + r);
        let ratio1 = self.test_ratio(z1 - y1, quaternion_dot(&ph1, &h1) + r);
        let worst = if ratio1 > ratio0 || ratio1.is_nan() {
            ratio1
        } else {
            ratio0
        };
        let outcome = Fusion::from_ratio(worst);
        if outcome.is_fused() {
            let u0 = self.sequential_row(&[], ph0, |v| quaternion_dot(v, &h0), r, z0 - y0);
            // The second row re-linearised at the state the first left (cheap, no trig).
            let ([_, y1], [_, h1]) = heading_field(self.attitude(), [b0, b1]);
            let ph1 = self.p_h(&h1);
            let u1 = self.sequential_row(&[u0], ph1, |v| quaternion_dot(v, &h1), r, z1 - y1);
            self.subtract_outers(&[u0, u1, [0.0; STATES]]);
            self.finish_update()?;
        }
        Ok(outcome)
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

/// h·v for an H row that is non-zero only on the quaternion.
#[inline(always)]
fn quaternion_dot(v: &[f32; STATES], h: &[f32; 4]) -> f32 {
    v.iter()
        .skip(index::QUATERNION)
        .zip(h.iter())
        .map(|(a, b)| a * b)
        .sum()
}
