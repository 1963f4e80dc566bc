//! Attitude and navigation estimators: a complementary attitude filter for flight without
//! GPS, and the 14-state INS/GPS extended Kalman filter, plus the magnetometer's hard- and
//! soft-iron calibration they rely on. All sans-IO, no globals: every estimator is a plain
//! value, so several can run side by side.
//!
//! A crate of its own, re-exported as `flight_core::estimation`: the flight loop's hot
//! numerics (the INS covariance above all) are built at `opt-level = 3` while the rest of
//! the flight core is built for size (see the workspace manifest's profiles).
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod align;
pub mod complementary;
pub mod ins;
pub use magcal;
pub mod math;
pub mod quaternion;

/// Standard gravity used by the process models (m/s²), as in the Tau Labs INS.
pub const GRAVITY_MPS2: f32 = 9.805;

/// Why an estimator refused an input. Rejected *measurements* are not errors: they are
/// reported as outcomes ([`ins::Fusion`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// An input value was NaN or infinite; the estimator state was left untouched.
    NonFinite,
    /// The time step was not strictly positive or was implausibly long.
    InvalidTimeStep,
    /// The estimator's own state became non-finite; it must be re-initialised.
    Diverged,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NonFinite => f.write_str("non-finite input refused"),
            Self::InvalidTimeStep => f.write_str("time step out of range"),
            Self::Diverged => f.write_str("estimator state is no longer finite"),
        }
    }
}

impl core::error::Error for Error {}

/// Whether every value is finite, with one compare: `v * 0.0` is ±0 for a finite `v` and
/// NaN for ±∞ or NaN, and a NaN survives the sum. A test per value costs ≈ 5 instructions
/// on the M4F (compare, flag transfer, branch); this one ≈ 1 per value.
#[inline]
pub fn all_finite(values: &[f32]) -> bool {
    values.iter().fold(0.0_f32, |s, v| s + v * 0.0) == 0.0
}

/// `Ok(())` when every value is finite.
pub(crate) fn check_finite(values: &[f32]) -> Result<(), Error> {
    if all_finite(values) {
        Ok(())
    } else {
        Err(Error::NonFinite)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn all_finite_is_false_for_any_nan_or_infinity() {
        let finite = [0.0, -0.0, 1.0, -3.4e38, 3.4e38, 1e-45];
        assert!(all_finite(&finite));
        assert!(all_finite(&[]));
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for i in 0..finite.len() {
                let mut v = finite;
                if let Some(x) = v.get_mut(i) {
                    *x = bad;
                }
                assert!(!all_finite(&v), "{v:?}");
                assert_eq!(check_finite(&v), Err(Error::NonFinite));
            }
        }
    }
}
