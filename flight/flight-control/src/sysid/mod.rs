//! System identification and autotune: the shake excitation, the (ω, ν, b, ln β; ln τ)
//! identification EKF and the gains derived from its result.

pub mod autotune;
pub mod ekf;
pub mod shake;

pub use ekf::{Identification, SysidConfig, SystemIdentifier};
