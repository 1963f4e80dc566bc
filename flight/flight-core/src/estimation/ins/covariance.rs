//! Covariance bookkeeping shared by prediction, fusion and resets. The fusion steps update
//! only the upper triangle and mirror it, so P is symmetric by construction.

use super::{Covariance, STATES};

/// Column `k` of P (= row `k`, P being symmetric).
pub(super) fn column(p: &Covariance, k: usize) -> [f32; STATES] {
    p.get(k).copied().unwrap_or([0.0; STATES])
}

/// P ← P − (ph·phᵀ)/s on the upper triangle, then mirrored (the scalar Kalman update
/// P − K·H·P with K = ph/s).
pub(super) fn subtract_outer(p: &mut Covariance, ph: &[f32; STATES], inv_s: f32) {
    for (i, (row, &ph_i)) in p.iter_mut().zip(ph.iter()).enumerate() {
        let k_i = ph_i * inv_s;
        for (p_ij, &ph_j) in row.iter_mut().zip(ph.iter()).skip(i) {
            *p_ij -= k_i * ph_j;
        }
    }
    mirror_upper(p);
}

/// Copies the upper triangle onto the lower one.
pub(super) fn mirror_upper(p: &mut Covariance) {
    for i in 1..STATES {
        let (upper, lower) = p.split_at_mut(i);
        if let Some(row) = lower.first_mut() {
            for (p_ij, upper_row) in row.iter_mut().zip(upper.iter()) {
                if let Some(&p_ji) = upper_row.get(i) {
                    *p_ij = p_ji;
                }
            }
        }
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
