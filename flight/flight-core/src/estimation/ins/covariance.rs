//! Covariance bookkeeping shared by prediction, fusion and resets. Every write keeps P
//! exactly (bitwise) symmetric.

use super::{Covariance, STATES};

/// Column `k` of P (= row `k`, P being symmetric).
pub(super) fn column(p: &Covariance, k: usize) -> [f32; STATES] {
    p.get(k).copied().unwrap_or([0.0; STATES])
}

/// P ← P − (ph·phᵀ)/s, the scalar Kalman update P − K·H·P with K = ph/s. Written as
/// P − u·uᵀ with u = ph/√s: every element is one multiply-subtract and, the product being
/// commutative, P[i][j] and P[j][i] get bit-identical values, so P stays exactly symmetric
/// without a mirror pass or index arithmetic.
pub(super) fn subtract_outer(p: &mut Covariance, ph: &[f32; STATES], s: f32) {
    let scale = crate::estimation::math::inv_sqrt(s);
    let u = ph.map(|v| v * scale);
    for (row, &u_i) in p.iter_mut().zip(u.iter()) {
        for (p_ij, &u_j) in row.iter_mut().zip(u.iter()) {
            *p_ij -= u_i * u_j;
        }
    }
}

/// P[i][j] (0 outside the matrix, which the callers' index ranges never reach).
#[inline(always)]
pub(super) fn get(p: &Covariance, i: usize, j: usize) -> f32 {
    p.get(i).and_then(|row| row.get(j)).copied().unwrap_or(0.0)
}

/// P[i][j] = P[j][i] = v.
#[inline(always)]
pub(super) fn set_symmetric(p: &mut Covariance, i: usize, j: usize, v: f32) {
    if let Some(x) = p.get_mut(i).and_then(|row| row.get_mut(j)) {
        *x = v;
    }
    if let Some(x) = p.get_mut(j).and_then(|row| row.get_mut(i)) {
        *x = v;
    }
}

/// Keeps every variance at least `floor`; an update that rounding pushed to zero or below
/// would otherwise stop P from being positive definite.
pub(super) fn floor_diagonal(p: &mut Covariance, floor: f32) {
    for (i, row) in p.iter_mut().enumerate() {
        if let Some(d) = row.get_mut(i)
            && (d.is_nan() || *d < floor)
        {
            *d = floor;
        }
    }
}

/// Zeroes rows and columns `first..first+count` (before a reset writes a fresh block).
pub(super) fn clear_block(p: &mut Covariance, first: usize, count: usize) {
    let range = first..first + count;
    for (i, row) in p.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            if range.contains(&i) || range.contains(&j) {
                *v = 0.0;
            }
        }
    }
}

/// Sets P[first+a][first+b] = block[a][b] for a 4×4 block on the diagonal.
pub(super) fn set_block4(p: &mut Covariance, first: usize, block: &[[f32; 4]; 4]) {
    for (row, block_row) in p.iter_mut().skip(first).zip(block.iter()) {
        for (v, &b) in row.iter_mut().skip(first).zip(block_row.iter()) {
            *v = b;
        }
    }
}
