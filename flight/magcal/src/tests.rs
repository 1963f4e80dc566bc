//! Synthetic rotations with known hard and soft iron and noise: recovered, checked, refused.
#![allow(clippy::needless_range_loop)] // 3×3 matrix arithmetic reads better indexed

use super::*;

/// Deterministic xorshift noise, roughly normal (sum of 4 uniforms, scaled to σ = 1).
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let s: f64 = (0..4).map(|_| self.uniform()).sum();
        (s - 2.0) * (3.0_f64).sqrt()
    }
}

const FIELD: f64 = 0.5; // gauss
const OFFSET: [f64; 3] = [0.21, -0.12, 0.33];
/// Symmetric soft iron: raw = SOFT · true + OFFSET.
const SOFT: [[f64; 3]; 3] = [[1.20, 0.08, -0.03], [0.08, 0.90, 0.05], [-0.03, 0.05, 1.05]];

fn distort(b: [f64; 3], noise: &mut Noise, sigma: f64) -> [f32; 3] {
    let mut out = [0f32; 3];
    for r in 0..3 {
        let v: f64 = (0..3).map(|c| SOFT[r][c] * b[c]).sum();
        out[r] = (v + OFFSET[r] + sigma * noise.normal()) as f32;
    }
    out
}

/// Field directions of a frame turned through every orientation (a Fibonacci sphere).
fn all_orientations(n: usize, sigma: f64) -> Vec<[f32; 3]> {
    let mut noise = Noise(0x9E37_79B9_7F4A_7C15);
    let golden = std::f64::consts::PI * (3.0 - 5.0_f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let a = golden * i as f64;
            distort(
                [FIELD * r * a.cos(), FIELD * r * a.sin(), FIELD * z],
                &mut noise,
                sigma,
            )
        })
        .collect()
}

#[test]
fn recovers_offset_and_sphere_from_a_full_rotation() {
    let samples = all_orientations(400, 0.002); // 0.4 % noise
    let cal = fit(&samples, &MagCalConfig::default()).unwrap();
    for (got, want) in cal.offset.iter().zip(OFFSET) {
        assert!((f64::from(*got) - want).abs() < 0.005, "{:?}", cal.offset);
    }
    assert!(cal.residual_pct < 1.0, "{}", cal.residual_pct);
    assert!(cal.coverage > 0.9, "{}", cal.coverage);
    // matrix · SOFT is a multiple of the identity (the shape is undone, a scale remains).
    let mut prod = [[0f64; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            prod[r][c] = (0..3)
                .map(|k| f64::from(cal.matrix[r][k]) * SOFT[k][c])
                .sum();
        }
    }
    let s = prod[0][0];
    for r in 0..3 {
        for c in 0..3 {
            let want = if r == c { s } else { 0.0 };
            assert!((prod[r][c] - want).abs() < 0.01 * s, "{prod:?}");
        }
    }
    // Calibrated readings lie on a sphere of the reported field.
    for raw in &samples {
        let m = cal.apply(*raw);
        let norm = (m.iter().map(|v| v * v).sum::<f32>()).sqrt();
        assert!((norm - cal.field).abs() < 0.02 * cal.field);
    }
}

#[test]
fn noiseless_fit_is_exact() {
    let cal = fit(&all_orientations(200, 0.0), &MagCalConfig::default()).unwrap();
    assert!(cal.residual_pct < 0.01, "{}", cal.residual_pct);
    for (got, want) in cal.offset.iter().zip(OFFSET) {
        assert!((f64::from(*got) - want).abs() < 1e-4);
    }
}

#[test]
fn refuses_a_single_plane_rotation() {
    // Yaw only, level: the field's vertical part never changes.
    let mut noise = Noise(7);
    let incl = 1.1_f64; // 63° inclination
    let samples: Vec<[f32; 3]> = (0..300)
        .map(|i| {
            let psi = i as f64 * 0.05;
            let h = FIELD * incl.cos();
            distort(
                [h * psi.cos(), -h * psi.sin(), FIELD * incl.sin()],
                &mut noise,
                0.002,
            )
        })
        .collect();
    assert_eq!(
        fit(&samples, &MagCalConfig::default()),
        Err(MagCalError::SinglePlane)
    );
}

#[test]
fn refuses_too_little_rotation() {
    // Tilts within ±15° of level and a little yaw: a small patch of the ellipsoid.
    let mut noise = Noise(11);
    let samples: Vec<[f32; 3]> = (0..300)
        .map(|_| {
            let a = (noise.uniform() - 0.5) * 0.5;
            let b = (noise.uniform() - 0.5) * 0.5;
            let d = [0.45 + 0.3 * a, 0.3 * b, 0.2];
            let n = (d.iter().map(|v| v * v).sum::<f64>()).sqrt();
            distort(d.map(|v| FIELD * v / n), &mut noise, 0.002)
        })
        .collect();
    assert_eq!(
        fit(&samples, &MagCalConfig::default()),
        Err(MagCalError::TooLittleRotation)
    );
}

#[test]
fn refuses_too_few_samples_and_non_finite() {
    let samples = all_orientations(50, 0.002);
    assert_eq!(
        fit(&samples, &MagCalConfig::default()),
        Err(MagCalError::TooFewSamples {
            have: 50,
            need: 100
        })
    );
    let mut samples = all_orientations(200, 0.002);
    samples[17][1] = f32::NAN;
    assert_eq!(
        fit(&samples, &MagCalConfig::default()),
        Err(MagCalError::NonFinite)
    );
}

#[test]
fn refuses_a_high_residual() {
    // 10 % noise: a sphere cannot be told from the scatter.
    let samples = all_orientations(400, 0.05);
    assert!(matches!(
        fit(&samples, &MagCalConfig::default()),
        Err(MagCalError::HighResidual { .. })
    ));
}

#[test]
fn jacobi_eigen_agrees_with_nalgebra() {
    let mut noise = Noise(3);
    for _ in 0..200 {
        let mut m = [[0f32; 3]; 3];
        for r in 0..3 {
            for c in r..3 {
                let v = (noise.normal() * 10f64.powf(noise.normal())) as f32;
                m[r][c] = v;
                m[c][r] = v;
            }
        }
        let (values, vectors) = symmetric_eigen(m);
        // The reference in f64 on the same (f32) matrix; the solver's error is f32's.
        let m64 = m.map(|row| row.map(f64::from));
        let reference = nalgebra::Matrix3::from_fn(|r, c| m64[r][c]).symmetric_eigen();
        let mut got = values.map(f64::from);
        let mut want: Vec<f64> = reference.eigenvalues.iter().copied().collect();
        got.sort_by(f64::total_cmp);
        want.sort_by(f64::total_cmp);
        let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() <= 1e-6 * scale, "{got:?} {want:?}");
        }
        // m·v = λ·v for each vector (in f64), and the vectors are orthonormal.
        for k in 0..3 {
            let v = vectors[k].map(f64::from);
            for r in 0..3 {
                let mv: f64 = (0..3).map(|c| m64[r][c] * v[c]).sum();
                let lv = f64::from(values[k]) * v[r];
                assert!((mv - lv).abs() <= 1e-6 * scale, "{m:?}");
            }
            for j in 0..3 {
                let want = if j == k { 1.0 } else { 0.0 };
                assert!((dot(vectors[k], vectors[j]) - want).abs() < 1e-6);
            }
        }
    }
}

#[test]
fn cube_root_is_correct_to_round_off() {
    let mut x = 1e-30f32;
    while x < 1e30 {
        for v in [x, x * 1.37, x * 2.9] {
            let got = cube_root(v);
            assert!(
                (got - v.cbrt()).abs() <= 2.0 * f32::EPSILON * v.cbrt(),
                "{v}"
            );
        }
        x *= 10.0;
    }
}

#[test]
fn linear_solve_pivots_and_refuses_singular() {
    // A zero first pivot in a 3×3 block, the rest of the 9×9 a scaled identity.
    let mut a = [[0.0; QUADRIC]; QUADRIC];
    a[0][..3].copy_from_slice(&[0.0, 2.0, 1.0]);
    a[1][..3].copy_from_slice(&[1.0, 1.0, 0.0]);
    a[2][..3].copy_from_slice(&[3.0, 0.0, 1.0]);
    for k in 3..QUADRIC {
        a[k][k] = k as f32;
    }
    let want = [1.0f32, -2.0, 0.5, 3.0, -1.0, 0.25, 7.0, -0.5, 2.0];
    let mut b = [0.0; QUADRIC];
    for r in 0..QUADRIC {
        b[r] = (0..QUADRIC).map(|c| a[r][c] * want[c]).sum();
    }
    let x = solve_linear(a, b).unwrap();
    for r in 0..QUADRIC {
        assert!((x[r] - want[r]).abs() < 1e-6, "{x:?}");
    }
    a[2][..3].copy_from_slice(&[1.0, 3.0, 1.0]); // row 0 + row 1
    assert_eq!(solve_linear(a, b), None);
}
