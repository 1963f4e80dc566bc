//! Magnetometer calibration: hard iron (an offset) and soft iron (a symmetric shape matrix)
//! from readings taken while the frame is turned through every orientation. The readings
//! of an ideal magnetometer lie on a sphere; iron on the frame turns it into an ellipsoid
//! off the origin. A least-squares fit of the general quadric
//! `a x² + b y² + c z² + 2d xy + 2e xz + 2f yz + 2g x + 2h y + 2i z = 1`
//! gives the ellipsoid; its centre is the offset and the symmetric square root of its
//! shape, scaled to determinant 1 (so the field keeps its size), is the matrix:
//! `calibrated = matrix · (raw − offset)`.
//!
//! Before a result is accepted it is checked, as the Tau Labs calibration was by eye
//! ("the calibrated readings make a round circle"): enough samples, a rotation that is not
//! confined to one plane or a small patch, calibrated directions that cover the sphere,
//! and calibrated magnitudes that agree (the residual). Pure, no heap: the caller owns the
//! samples (the firmware keeps a bounded buffer while the owner turns the frame).

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::settings::decimal::Fixed;

/// Limits a calibration must meet.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MagCalConfig {
    /// Fewest samples.
    pub min_samples: usize,
    /// Smallest ratio of the raw readings' least to largest spread (variance): below it
    /// the rotation stayed in one plane or covered too little.
    pub min_spread_ratio: f64,
    /// Smallest coverage of calibrated directions (3 × the least eigenvalue of their
    /// mean outer product: 1 for a uniform sphere, 0 for one plane).
    pub min_coverage: f64,
    /// Largest residual accepted (relative RMS deviation of calibrated magnitudes, %).
    pub max_residual_pct: f64,
}

impl Default for MagCalConfig {
    /// 100 samples (a 20 s turn at 5 Hz); spread ratio 0.02 (a tilt of ±10° out of the
    /// plane of rotation gives ~0.01, turning each axis up once gives > 0.2); coverage 0.3;
    /// residual 3 % (the AK8963 at 0.15 µT/LSB on a 50 µT field sits near 0.5 %).
    fn default() -> Self {
        Self {
            min_samples: 100,
            min_spread_ratio: 0.02,
            min_coverage: 0.3,
            max_residual_pct: 3.0,
        }
    }
}

/// An accepted calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MagCalibration {
    /// Hard-iron offset (raw units).
    pub offset: [f32; 3],
    /// Soft-iron matrix, row-major, symmetric, determinant 1.
    pub matrix: [[f32; 3]; 3],
    /// Mean calibrated magnitude (raw units).
    pub field: f32,
    /// Relative RMS deviation of the calibrated magnitudes (%).
    pub residual_pct: f32,
    /// Coverage of calibrated directions (see [`MagCalConfig::min_coverage`]).
    pub coverage: f32,
}

impl MagCalibration {
    /// `matrix · (raw − offset)`.
    #[must_use]
    pub fn apply(&self, raw: [f32; 3]) -> [f32; 3] {
        let [r0, r1, r2] = raw;
        let [o0, o1, o2] = self.offset;
        let d = [r0 - o0, r1 - o1, r2 - o2];
        self.matrix.map(|row| {
            let [a, b, c] = row;
            let [x, y, z] = d;
            a * x + b * y + c * z
        })
    }
}

/// Why the data cannot determine a calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MagCalError {
    /// Fewer samples than needed.
    TooFewSamples {
        /// Samples given.
        have: usize,
        /// Samples needed.
        need: usize,
    },
    /// A sample was NaN or infinite.
    NonFinite,
    /// The readings go round one plane: the frame was turned about one axis only.
    SinglePlane,
    /// The readings cover too small a patch (or arc) of the ellipsoid.
    TooLittleRotation,
    /// The fitted quadric is not an ellipsoid (data too noisy or not a rotation at all).
    NotAnEllipsoid,
    /// The calibrated magnitudes disagree more than allowed.
    HighResidual {
        /// The residual (%).
        residual_pct: f32,
    },
}

impl core::fmt::Display for MagCalError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooFewSamples { have, need } => {
                write!(f, "too few samples: {have}, at least {need} needed")
            }
            Self::NonFinite => f.write_str("a sample is not a finite number"),
            Self::SinglePlane => f.write_str(
                "the rotation stayed in a single plane: turn the frame about all three axes",
            ),
            Self::TooLittleRotation => f.write_str(
                "too little rotation: turn the frame through every orientation (each axis up and down)",
            ),
            Self::NotAnEllipsoid => {
                f.write_str("the readings do not lie on an ellipsoid: no calibration fits")
            }
            Self::HighResidual { residual_pct } => write!(
                f,
                "calibrated magnitudes disagree by {} % RMS (too noisy, or iron moved)",
                Fixed(*residual_pct, 2)
            ),
        }
    }
}

impl core::error::Error for MagCalError {}

fn vec3(s: &[f32; 3]) -> Vector3<f64> {
    let [x, y, z] = *s;
    Vector3::new(f64::from(x), f64::from(y), f64::from(z))
}

/// Fits a calibration to `samples` and checks it against `config`.
///
/// # Errors
/// The first check the data fails ([`MagCalError`]).
pub fn fit(samples: &[[f32; 3]], config: &MagCalConfig) -> Result<MagCalibration, MagCalError> {
    let n = samples.len();
    if n < config.min_samples || n < 10 {
        return Err(MagCalError::TooFewSamples {
            have: n,
            need: config.min_samples.max(10),
        });
    }
    if samples.iter().flatten().any(|v| !v.is_finite()) {
        return Err(MagCalError::NonFinite);
    }
    let nf = n as f64;
    let mean = samples.iter().map(vec3).sum::<Vector3<f64>>() / nf;
    let cov = samples
        .iter()
        .map(|s| {
            let d = vec3(s) - mean;
            d * d.transpose()
        })
        .sum::<Matrix3<f64>>()
        / nf;
    check_spread(samples, &mean, &cov, config)?;

    // Fit in centred, scaled coordinates so the normal equations are well conditioned.
    let scale = libm::sqrt(cov.trace());
    let mut ata = SMatrix::<f64, 9, 9>::zeros();
    let mut atb = SVector::<f64, 9>::zeros();
    for s in samples {
        let p = (vec3(s) - mean) / scale;
        let (x, y, z) = (p.x, p.y, p.z);
        let phi = SVector::<f64, 9>::from([
            x * x,
            y * y,
            z * z,
            2.0 * x * y,
            2.0 * x * z,
            2.0 * y * z,
            2.0 * x,
            2.0 * y,
            2.0 * z,
        ]);
        ata += phi * phi.transpose();
        atb += phi;
    }
    let q = ata.lu().solve(&atb).ok_or(MagCalError::NotAnEllipsoid)?;
    let get = |i: usize| q.get(i).copied().unwrap_or(0.0);
    let m = Matrix3::new(
        get(0),
        get(3),
        get(4),
        get(3),
        get(1),
        get(5),
        get(4),
        get(5),
        get(2),
    );
    let v = Vector3::new(get(6), get(7), get(8));
    let centre = -(m.try_inverse().ok_or(MagCalError::NotAnEllipsoid)? * v);
    let k = 1.0 + (centre.transpose() * m * centre).x;
    if k.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
        return Err(MagCalError::NotAnEllipsoid);
    }
    let eig = (m / k).symmetric_eigen();
    if eig
        .eigenvalues
        .iter()
        .any(|&l| l.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater))
    {
        return Err(MagCalError::NotAnEllipsoid);
    }
    let sqrt_l = Matrix3::from_diagonal(&eig.eigenvalues.map(libm::sqrt));
    let w = eig.eigenvectors * sqrt_l * eig.eigenvectors.transpose();
    // Determinant 1: the shape is corrected, the size of the field kept.
    let matrix = w / libm::cbrt(w.determinant());
    let offset = mean + centre * scale;

    let cal = MagCalibration {
        offset: [offset.x as f32, offset.y as f32, offset.z as f32],
        matrix: [0, 1, 2]
            .map(|r| [0, 1, 2].map(|c| matrix.get((r, c)).copied().unwrap_or(0.0) as f32)),
        field: 0.0,
        residual_pct: 0.0,
        coverage: 0.0,
    };
    let (field, residual_pct, coverage) = quality(samples, &cal);
    let cal = MagCalibration {
        field: field as f32,
        residual_pct: residual_pct as f32,
        coverage: coverage as f32,
        ..cal
    };
    if coverage < config.min_coverage {
        return Err(MagCalError::TooLittleRotation);
    }
    // A NaN residual is refused too.
    if residual_pct.partial_cmp(&config.max_residual_pct) != Some(core::cmp::Ordering::Less) {
        return Err(MagCalError::HighResidual {
            residual_pct: cal.residual_pct,
        });
    }
    Ok(cal)
}

/// Rejects readings that span less than three dimensions. A ring (one-axis rotation) has
/// every reading about equally far from its mean; a small patch or arc does not.
fn check_spread(
    samples: &[[f32; 3]],
    mean: &Vector3<f64>,
    cov: &Matrix3<f64>,
    config: &MagCalConfig,
) -> Result<(), MagCalError> {
    let eig = cov.symmetric_eigen().eigenvalues;
    let max = eig.max();
    let min = eig.min();
    if max > 0.0 && min / max >= config.min_spread_ratio {
        return Ok(());
    }
    let nf = samples.len() as f64;
    let d: f64 = samples.iter().map(|s| (vec3(s) - mean).norm()).sum::<f64>() / nf;
    let var: f64 = samples
        .iter()
        .map(|s| {
            let e = (vec3(s) - mean).norm() - d;
            e * e
        })
        .sum::<f64>()
        / nf;
    // Coefficient of variation of the distance from the mean: ~0.1 for an ellipse
    // (a ring), ≥ 0.3 for a filled patch or an arc.
    if d > 0.0 && libm::sqrt(var) / d < 0.25 {
        Err(MagCalError::SinglePlane)
    } else {
        Err(MagCalError::TooLittleRotation)
    }
}

/// Mean calibrated magnitude, relative RMS deviation (%), direction coverage.
fn quality(samples: &[[f32; 3]], cal: &MagCalibration) -> (f64, f64, f64) {
    let nf = samples.len() as f64;
    let cals = || samples.iter().map(|s| vec3(&cal.apply(*s)));
    let field = cals().map(|c| c.norm()).sum::<f64>() / nf;
    let var = cals()
        .map(|c| {
            let e = c.norm() - field;
            e * e
        })
        .sum::<f64>()
        / nf;
    let residual_pct = if field > 0.0 {
        100.0 * libm::sqrt(var) / field
    } else {
        f64::INFINITY
    };
    let spread = cals()
        .filter_map(|c| c.try_normalize(1e-12))
        .map(|u| u * u.transpose())
        .sum::<Matrix3<f64>>()
        / nf;
    let coverage = 3.0 * spread.symmetric_eigen().eigenvalues.min();
    (field, residual_pct, coverage)
}

#[cfg(test)]
mod tests;
