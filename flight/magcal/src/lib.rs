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
//!
//! The arithmetic is f32, which a Cortex-M4F does in hardware: the readings are centred on
//! their mean and scaled to unit spread before the fit, so the normal equations stay well
//! conditioned and f32 recovers the calibration to well within the noise of any real
//! magnetometer (the crate's tests: 1e-6 of the field without noise). The 9-unknown least
//! squares is one Gaussian elimination with partial pivoting, the symmetric 3×3
//! eigenproblems cyclic Jacobi rotations — no linear-algebra crate, no libm beyond `sqrt`.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use float_text::Fixed;

/// Limits a calibration must meet.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MagCalConfig {
    /// Fewest samples.
    pub min_samples: usize,
    /// Smallest ratio of the raw readings' least to largest spread (variance): below it
    /// the rotation stayed in one plane or covered too little.
    pub min_spread_ratio: f32,
    /// Smallest coverage of calibrated directions (3 × the least eigenvalue of their
    /// mean outer product: 1 for a uniform sphere, 0 for one plane).
    pub min_coverage: f32,
    /// Largest residual accepted (relative RMS deviation of calibrated magnitudes, %).
    pub max_residual_pct: f32,
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

type Vec3 = [f32; 3];
type Mat3 = [[f32; 3]; 3];

fn add(a: Vec3, b: Vec3) -> Vec3 {
    let ([x, y, z], [p, q, r]) = (a, b);
    [x + p, y + q, z + r]
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    let ([x, y, z], [p, q, r]) = (a, b);
    [x - p, y - q, z - r]
}

fn dot(a: Vec3, b: Vec3) -> f32 {
    let ([x, y, z], [p, q, r]) = (a, b);
    x * p + y * q + z * r
}

fn norm(a: Vec3) -> f32 {
    libm::sqrtf(dot(a, a))
}

/// `m += w · a·aᵀ`.
fn add_outer(m: &mut Mat3, a: Vec3, w: f32) {
    for (row, ai) in m.iter_mut().zip(a) {
        for (e, aj) in row.iter_mut().zip(a) {
            *e += w * ai * aj;
        }
    }
}

/// Unknowns of the quadric fit.
const QUADRIC: usize = 9;

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
    let nf = n as f32;
    let sum = samples.iter().fold([0.0; 3], |acc, s| add(acc, *s));
    let mean = sum.map(|v| v / nf);
    let mut cov = [[0.0; 3]; 3];
    for s in samples {
        add_outer(&mut cov, sub(*s, mean), 1.0 / nf);
    }
    check_spread(samples, mean, &cov, config)?;

    // Fit in centred, scaled coordinates so the normal equations are well conditioned.
    let [[c0, ..], [_, c1, _], [.., c2]] = cov;
    let scale = libm::sqrtf(c0 + c1 + c2);
    let mut ata = [[0.0; QUADRIC]; QUADRIC];
    let mut atb = [0.0; QUADRIC];
    for s in samples {
        let [x, y, z] = sub(*s, mean).map(|v| v / scale);
        let phi = [
            x * x,
            y * y,
            z * z,
            2.0 * x * y,
            2.0 * x * z,
            2.0 * y * z,
            2.0 * x,
            2.0 * y,
            2.0 * z,
        ];
        for ((row, b), pi) in ata.iter_mut().zip(atb.iter_mut()).zip(phi) {
            for (e, pj) in row.iter_mut().zip(phi) {
                *e += pi * pj;
            }
            *b += pi;
        }
    }
    let [a, b, c, d, e, f, g, h, i] = solve_linear(ata, atb).ok_or(MagCalError::NotAnEllipsoid)?;
    // The quadric is (x − c)ᵀ·M·(x − c) = k with k = 1 + cᵀ·M·c and the centre solving
    // M·c = −v; an ellipsoid's M is positive definite. One eigen-decomposition
    // M = Σ λₖ·uₖ·uₖᵀ gives all three: c = −Σ (uₖ·v)/λₖ·uₖ, cᵀ·M·c = Σ (uₖ·v)²/λₖ, and
    // M/k has the eigenvalues λₖ/k on the same vectors.
    let (lambda, u) = symmetric_eigen([[a, d, e], [d, b, f], [e, f, c]]);
    if lambda
        .iter()
        .any(|&l| l.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater))
    {
        return Err(MagCalError::NotAnEllipsoid);
    }
    let (mut centre, mut k) = ([0.0; 3], 1.0);
    for (vector, l) in u.iter().zip(lambda) {
        let along = dot(*vector, [g, h, i]);
        centre = sub(centre, vector.map(|x| x * along / l));
        k += along * along / l;
    }
    // Also refuses NaN.
    if k.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
        return Err(MagCalError::NotAnEllipsoid);
    }
    let lambda = lambda.map(|l| l / k);
    // W = Σ √λₖ·uₖ·uₖᵀ maps the ellipsoid onto a sphere; det W = √(λ₀λ₁λ₂), so W scaled
    // to determinant 1 (the shape corrected, the size of the field kept) takes √(λₖ/γ),
    // γ the geometric mean of the λ.
    let [l0, l1, l2] = lambda;
    let gamma = cube_root(l0 * l1 * l2);
    let root = lambda.map(|l| libm::sqrtf(l / gamma));
    let mut w = [[0.0; 3]; 3];
    for (vector, r) in u.iter().zip(root) {
        add_outer(&mut w, *vector, r);
    }
    let offset = add(mean, centre.map(|c| c * scale));

    let cal = MagCalibration {
        offset,
        matrix: w,
        field: 0.0,
        residual_pct: 0.0,
        coverage: 0.0,
    };
    let (field, residual_pct, coverage) = quality(samples, &cal);
    let cal = MagCalibration {
        field,
        residual_pct,
        coverage,
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
    mean: Vec3,
    cov: &Mat3,
    config: &MagCalConfig,
) -> Result<(), MagCalError> {
    let (eig, _) = symmetric_eigen(*cov);
    let max = eig.iter().copied().fold(f32::MIN, f32::max);
    let min = eig.iter().copied().fold(f32::MAX, f32::min);
    if max > 0.0 && min / max >= config.min_spread_ratio {
        return Ok(());
    }
    let about_mean = MagCalibration {
        offset: mean,
        matrix: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        field: 0.0,
        residual_pct: 0.0,
        coverage: 0.0,
    };
    let (d, rms) = magnitudes(samples, &about_mean);
    // Coefficient of variation of the distance from the mean: ~0.1 for an ellipse
    // (a ring), ≥ 0.3 for a filled patch or an arc.
    if d > 0.0 && rms / d < 0.25 {
        Err(MagCalError::SinglePlane)
    } else {
        Err(MagCalError::TooLittleRotation)
    }
}

/// The mean and the RMS deviation of the calibrated readings' magnitudes.
fn magnitudes(samples: &[[f32; 3]], cal: &MagCalibration) -> (f32, f32) {
    let nf = samples.len() as f32;
    let lengths = || samples.iter().map(|s| norm(cal.apply(*s)));
    let mean = lengths().sum::<f32>() / nf;
    let var = lengths()
        .map(|l| {
            let e = l - mean;
            e * e
        })
        .sum::<f32>()
        / nf;
    (mean, libm::sqrtf(var))
}

/// Mean calibrated magnitude, relative RMS deviation (%), direction coverage.
fn quality(samples: &[[f32; 3]], cal: &MagCalibration) -> (f32, f32, f32) {
    let nf = samples.len() as f32;
    let cals = || samples.iter().map(|s| cal.apply(*s));
    let (field, rms) = magnitudes(samples, cal);
    let residual_pct = if field > 0.0 {
        100.0 * rms / field
    } else {
        f32::INFINITY
    };
    let mut spread = [[0.0; 3]; 3];
    for c in cals() {
        let length = norm(c);
        if length > 1e-30 {
            add_outer(&mut spread, c.map(|v| v / length), 1.0 / nf);
        }
    }
    let (eig, _) = symmetric_eigen(spread);
    let coverage = 3.0 * eig.iter().copied().fold(f32::MAX, f32::min);
    (field, residual_pct, coverage)
}

/// Solves the quadric's normal equations `a·x = b` by Gaussian elimination with partial
/// pivoting; `None` when a pivot vanishes.
fn solve_linear(mut a: [[f32; QUADRIC]; QUADRIC], mut b: [f32; QUADRIC]) -> Option<[f32; QUADRIC]> {
    let n = QUADRIC;
    for k in 0..n {
        let magnitude = |i: &usize| a.get(*i).and_then(|r| r.get(k)).map_or(0.0, |v| v.abs());
        let pivot = (k..n).max_by(|i, j| magnitude(i).total_cmp(&magnitude(j)))?;
        a.swap(k, pivot);
        b.swap(k, pivot);
        let (upper, lower) = a.split_at_mut(k + 1);
        let (b_upper, b_lower) = b.split_at_mut(k + 1);
        let (row_k, &b_k) = (upper.last()?, b_upper.last()?);
        let p = *row_k.get(k)?;
        if p == 0.0 || !p.is_finite() {
            return None;
        }
        for (row, bi) in lower.iter_mut().zip(b_lower.iter_mut()).take(n - k - 1) {
            let factor = row.get(k)? / p;
            for (x, y) in row.iter_mut().zip(row_k).take(n).skip(k) {
                *x -= factor * y;
            }
            *bi -= factor * b_k;
        }
    }
    let mut x = [0.0; QUADRIC];
    for k in (0..n).rev() {
        let row = a.get(k)?;
        let known: f32 = row
            .iter()
            .zip(&x)
            .take(n)
            .skip(k + 1)
            .map(|(r, x)| r * x)
            .sum();
        let value = (b.get(k)? - known) / row.get(k)?;
        *x.get_mut(k)? = value;
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Eigenvalues of a symmetric 3×3 matrix and its orthonormal eigenvectors (the rows of
/// the second, in the same order), by cyclic Jacobi rotations — each zeroes one
/// off-diagonal entry; a few sweeps reach round-off.
/// Jacobi stops when Σ off² ≤ this · Σ diagonal²: (f32 epsilon / 8)², the off-diagonal
/// entries a small fraction of an ulp of the diagonal.
const JACOBI_TOLERANCE: f32 = (f32::EPSILON / 8.0) * (f32::EPSILON / 8.0);

fn symmetric_eigen(m: Mat3) -> (Vec3, Mat3) {
    let [[a00, a01, a02], [_, a11, a12], [.., a22]] = m;
    let mut diagonal = [a00, a11, a22];
    // off[r] = a[p][q] for {p, q, r} = {0, 1, 2}.
    let mut off = [a12, a02, a01];
    let mut vectors = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..32 {
        let size = diagonal.iter().map(|v| v * v).sum::<f32>();
        let rest = off.iter().map(|v| v * v).sum::<f32>();
        // Off-diagonal below f32 round-off of the diagonal; also stops on NaN.
        if rest.partial_cmp(&(JACOBI_TOLERANCE * size)) != Some(core::cmp::Ordering::Greater) {
            break;
        }
        for (p, q, r) in [(0, 1, 2), (0, 2, 1), (1, 2, 0)] {
            rotate(&mut diagonal, &mut off, &mut vectors, [p, q, r]);
        }
    }
    (diagonal, vectors)
}

/// One Jacobi rotation J in the (p, q) plane, r the third axis: `a ← Jᵀ·a·J` with a[p][q]
/// becoming 0, and the eigenvector rows p and q turned alike.
#[inline(never)]
fn rotate(diagonal: &mut Vec3, off: &mut Vec3, vectors: &mut Mat3, [p, q, r]: [usize; 3]) {
    let (Ok([app, aqq]), Ok([apq, apr, aqr])) = (
        diagonal.get_disjoint_mut([p, q]),
        off.get_disjoint_mut([r, q, p]),
    ) else {
        return;
    };
    if *apq == 0.0 {
        return;
    }
    // t = tan of the rotation angle, the smaller root of t² + 2θt − 1 = 0.
    let theta = (*aqq - *app) / (2.0 * *apq);
    // Past 1e18, θ² + 1 would overflow f32; there t ≈ 1/(2θ).
    let t = if theta.abs() > 1e18 {
        0.5 / theta
    } else {
        let t = 1.0 / (theta.abs() + libm::sqrtf(theta * theta + 1.0));
        if theta < 0.0 { -t } else { t }
    };
    let c = 1.0 / libm::sqrtf(t * t + 1.0);
    let s = t * c;
    let turn = |x: &mut f32, y: &mut f32| {
        let (a, b) = (*x, *y);
        *x = c * a - s * b;
        *y = s * a + c * b;
    };
    *app -= t * *apq;
    *aqq += t * *apq;
    *apq = 0.0;
    turn(apr, aqr);
    if let Ok([vp, vq]) = vectors.get_disjoint_mut([p, q]) {
        for (x, y) in vp.iter_mut().zip(vq.iter_mut()) {
            turn(x, y);
        }
    }
}

/// x^(1/3) for a finite x > 0: Newton's iteration y ← (2y + x/y²)/3 from the exponent
/// divided by three (within ≈ 10 %), five steps to round-off: one call per calibration,
/// where libm's `cbrtf` would be flash for nothing.
fn cube_root(x: f32) -> f32 {
    const ONE_THIRD_BIAS: u32 = (127 - 127 / 3) << 23;
    let mut y = f32::from_bits(x.to_bits() / 3 + ONE_THIRD_BIAS);
    for _ in 0..5 {
        y = (2.0 * y + x / (y * y)) / 3.0;
    }
    y
}

#[cfg(test)]
mod tests;
