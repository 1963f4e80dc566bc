//! Covariance bookkeeping shared by prediction, fusion and resets. Every write keeps P
//! exactly (bitwise) symmetric.

use super::{Covariance, STATES};

/// Column `k` of P (= row `k`, P being symmetric).
pub(super) fn column(p: &Covariance, k: usize) -> [f32; STATES] {
    p.get(k).copied().unwrap_or([0.0; STATES])
}

/// How many scalar rows one covariance pass takes at most (a GPS position or velocity).
pub(super) const ROWS: usize = 3;

/// P ← P − Σₖ uₖ·uₖᵀ: the covariance part of up to [`ROWS`] sequential scalar Kalman
/// updates, each P − K·H·P = P − u·uᵀ with u = P·hᵀ/√s (P·hᵀ taken after the earlier rows,
/// see `fusion::Filter::sequential_row`; unused rows are zeros), applied in one pass. Only
/// the upper triangle is formed and each value is stored to both halves, so P stays exactly
/// symmetric; one pass for three rows loads and stores P once instead of three times. Each
/// row is its own instance (`I` constant), so its columns unroll with constant offsets: a
/// rolled loop spent as many instructions on indices as on the arithmetic.
pub(super) fn subtract_outers(p: &mut Covariance, u: &[[f32; STATES]; ROWS]) {
    macro_rules! rows {
        ($($i:literal)*) => { $( subtract_row::<$i>(p, u); )* };
    }
    rows!(0 1 2 3 4 5 6 7 8 9 10 11 12 13);
}

/// Row `I` of [`subtract_outers`], columns I.. .
#[inline(always)]
fn subtract_row<const I: usize>(p: &mut Covariance, u: &[[f32; STATES]; ROWS]) {
    let ui: [f32; ROWS] = core::array::from_fn(|k| cell(u, k, I));
    for j in I..STATES {
        let mut v = get(p, I, j);
        for (k, &uik) in ui.iter().enumerate() {
            v -= uik * cell(u, k, j);
        }
        set_symmetric(p, I, j, v);
    }
}

/// `u[k][i]` (0 outside).
#[inline(always)]
fn cell(u: &[[f32; STATES]; ROWS], k: usize, i: usize) -> f32 {
    u.get(k).and_then(|row| row.get(i)).copied().unwrap_or(0.0)
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
