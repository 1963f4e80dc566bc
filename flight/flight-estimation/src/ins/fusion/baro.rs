//! Barometric altitude: h = −pD (DERIVATION.md §4), fused as a direct observation of pD
//! with the measurement negated.

use super::Fusion;
use crate::ins::{Filter, index};
use crate::{Error, check_finite};

impl Filter {
    /// Fuses a barometric altitude (m, up-positive, relative to the same origin as the
    /// position states).
    ///
    /// # Errors
    /// [`Error::NonFinite`] for non-finite input, [`Error::Diverged`] if the update failed.
    pub fn fuse_baro(&mut self, altitude_m: f32) -> Result<Fusion, Error> {
        check_finite(&[altitude_m])?;
        let k = index::POSITION + 2;
        let r = self.config.baro_var_m2;
        let outcome = Fusion::from_ratio(self.direct_test(k, -altitude_m, r));
        if outcome.is_fused() {
            self.fuse_direct([(k, r)], [-altitude_m]);
            self.finish_update()?;
        }
        Ok(outcome)
    }
}
