//! The LQG controller's model and gain design, as the flight controller runs it before
//! take-off (and the host tools run it to plan one):
//!
//! - [`model`]: one rotation axis as θ' = ω, ω' = (β1 − β2)·ν + β2·u, ν' = (u − ν)/τ
//!   ([`model::AxisModel`], β stored as ln β) and its exact zero-order-hold discretisation in
//!   a form that stays accurate in f32 ([`model::discrete`], generic over f32 and f64);
//! - [`dare`]: the discrete algebraic Riccati equation by structure-preserving doubling, in
//!   f64, with its residual and stability checks;
//! - [`design`]: the steady-state Kalman gain of the rate/torque/bias estimator and the LQR
//!   gains for rate and attitude ([`design::design_axis`]).
//!
//! `LQG.md` in the doc comments is the controller's design document,
//! `flight/flight-core/src/control/LQG.md`; the controller that flies these gains (RTKF and
//! LQR in f32) is `flight-core`'s `control`. The design runs once per settings change, so
//! this crate is built for size (the workspace's `[profile.release.package.lqg-design]`):
//! its f64 arithmetic is soft-float on the Cortex-M4F and unrolled it was 10 KB of flash;
//! the flight-time f32 instances of [`model::discrete`] are compiled where they are used.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod dare;
pub mod design;
mod exp;
pub mod model;
