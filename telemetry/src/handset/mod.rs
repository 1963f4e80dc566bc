//! Handset-side wire formats of the TauLink module: CRSF to and from the radio on the JR
//! bay, FrSky S.Port push and FrSky D hub frames for PPM mode. Pure codecs and schedulers:
//! bytes in, bytes out, time passed in. What is byte-exact against what: `README.md` here.

pub mod crsf;
pub mod frsky_d;
pub mod report;
pub mod sport;
pub mod stuffing;

pub use report::HandsetTelemetry;
