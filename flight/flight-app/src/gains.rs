//! Building the controller bank, the one place the application and the firmware do it:
//! the gain folding and the controllers' constructors are `#[inline]` in `flight-core` and
//! `flight-control` (crates built for speed, for the loop), so they are compiled here, in
//! this crate built for size, and once — every caller goes through these two functions.

use crate::control::design::{AxisDesign, DesignError};
use crate::pipeline::{ControlParams, Controllers};

/// Solves the three axes' LQG gains for `p` and builds the controllers (the f64 Riccati
/// solves: ≈ 5.5 M instructions, never in the loop).
pub fn design(p: &ControlParams) -> Result<Controllers, DesignError> {
    Ok(rebuild(p, Controllers::solve(p)?))
}

/// The controllers `p` and the axes' Riccati solutions `designs` make, no solve
/// ([`Controllers::from_designs`]).
#[inline(never)]
pub fn rebuild(p: &ControlParams, designs: [AxisDesign; 3]) -> Controllers {
    Controllers::from_designs(p, designs)
}
