#![doc = include_str!("../README.md")]
// The README above is the crate's documentation (its examples run as doc tests); what each
// module owns is in the module's own `//!` doc.
#![cfg_attr(not(test), no_std)]
// docs.rs: the feature each gated item needs, shown beside it.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod crsf;
pub mod frsky_d;
pub mod report;
pub mod sport;
pub mod stuffing;

pub use report::HandsetTelemetry;
