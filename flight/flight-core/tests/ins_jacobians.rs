//! The hand-derived Jacobians (estimation/ins/DERIVATION.md) against central finite
//! differences of the models they linearise, at several operating points.

#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::needless_range_loop
)] // test code

use flight_core::estimation::ins::equations::{derivative, heading_field, process_jacobian};
use flight_core::estimation::quaternion::{from_euler, normalized};

const G: f32 = 9.805;

/// Operating points: (state, gyro, accel).
fn points() -> Vec<([f32; 14], [f32; 3], [f32; 3])> {
    let mut out = Vec::new();
    let attitudes = [
        (0.0, 0.0, 0.0),
        (0.3, -0.2, 1.0),
        (-1.2, 0.7, -2.5),
        (2.9, 0.1, 3.0),
    ];
    for (i, &(r, p, y)) in attitudes.iter().enumerate() {
        let q = from_euler(r, p, y);
        let k = i as f32;
        let x = [
            1.0,
            -2.0,
            3.0,
            0.5 * k,
            -1.0,
            0.2,
            q[0],
            q[1],
            q[2],
            q[3],
            0.01 * k,
            -0.02,
            0.03,
            0.1 * k,
        ];
        out.push((x, [0.1 + k, -0.3, 0.7 * k], [1.0 - k, 0.5, -G + k]));
    }
    out
}

fn fd_column(x: &[f32; 14], gyro: [f32; 3], accel: [f32; 3], j: usize) -> [f64; 14] {
    let h = 1e-3_f32;
    let mut plus = *x;
    let mut minus = *x;
    plus[j] += h;
    minus[j] -= h;
    let fp = derivative(&plus, gyro, accel, G);
    let fm = derivative(&minus, gyro, accel, G);
    std::array::from_fn(|i| {
        (f64::from(fp[i]) - f64::from(fm[i])) / (f64::from(plus[j]) - f64::from(minus[j]))
    })
}

#[test]
fn process_jacobian_matches_finite_differences() {
    for (x, gyro, accel) in points() {
        let jac = process_jacobian(&x, gyro, accel);
        // Assemble the full 14×14 F from its blocks.
        let mut f = [[0.0_f64; 14]; 14];
        for i in 0..3 {
            f[i][3 + i] = 1.0;
            for m in 0..4 {
                f[3 + i][6 + m] = f64::from(jac.dv_dq()[i][m]);
            }
            f[3 + i][13] = f64::from(jac.dv_dbaz()[i]);
        }
        for i in 0..4 {
            for m in 0..4 {
                f[6 + i][6 + m] = f64::from(jac.dq_dq()[i][m]);
            }
            for m in 0..3 {
                f[6 + i][10 + m] = f64::from(jac.dq_dbg()[i][m]);
            }
        }
        for j in 0..14 {
            let col = fd_column(&x, gyro, accel, j);
            for i in 0..14 {
                let err = (col[i] - f[i][j]).abs();
                assert!(
                    err < 1e-2 * (1.0 + f[i][j].abs()),
                    "F[{i}][{j}]: analytic {} vs numeric {}",
                    f[i][j],
                    col[i]
                );
            }
        }
    }
}

#[test]
fn heading_jacobian_matches_finite_differences() {
    let field = [400.0, 35.0];
    for (r, p, y) in [
        (0.0, 0.0, 0.0),
        (0.4, -0.3, 1.2),
        (-0.9, 0.5, -2.8),
        (0.1, 0.2, 3.1),
    ] {
        // Also off the unit sphere: the model is homogeneous in |q|, H must follow that.
        for scale in [1.0_f32, 1.3] {
            let q = normalized(from_euler(r, p, y)).map(|c| c * scale);
            let (_, h) = heading_field(q, field);
            for m in 0..4 {
                let step = 1e-3_f32;
                let mut qp = q;
                let mut qm = q;
                qp[m] += step;
                qm[m] -= step;
                let (yp, _) = heading_field(qp, field);
                let (ym, _) = heading_field(qm, field);
                for row in 0..2 {
                    let numeric = (f64::from(yp[row]) - f64::from(ym[row]))
                        / (f64::from(qp[m]) - f64::from(qm[m]));
                    let analytic = f64::from(h[row][m]);
                    assert!(
                        (numeric - analytic).abs() < 0.5 + 2e-3 * analytic.abs(),
                        "H[{row}][{m}] at {r},{p},{y}×{scale}: {analytic} vs {numeric}"
                    );
                }
            }
        }
    }
}
