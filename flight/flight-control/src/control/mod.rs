//! Rate and attitude control: the LQG (RTKF estimator + LQR), its gain design, the PID
//! default/baseline and the motor mixer.

pub use lqg_design::{dare, design};
pub mod lqr;
pub mod mixer;
pub mod pid;
pub mod rtkf;
