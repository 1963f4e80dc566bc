//! The runner (in progress).
pub mod binding;
pub mod image;
