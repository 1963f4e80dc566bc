//! Both TauLink ends — the real module-side and flight-side link code — running against
//! each other in a simulated RF medium, in virtual time: the project's main job.
//!
//! The radios are `telemetry::mock` packet-level radios (settle time and airtime charged
//! as on the Si4432). [`world`] builds a scenario, [`probe`] holds the application ends that
//! measure, [`report`] summarises.
#![warn(missing_docs)]

pub mod attack;
pub mod chip_world;
pub mod cli;
pub mod docs;
pub mod driver;
mod ends;
pub mod handset;
mod json;
pub mod openlrs;
pub mod plot;
pub mod ppm_input;
pub mod probe;
pub mod report;
pub mod scenario;
pub mod serve;
pub mod sweep;
pub mod walk;
pub mod world;

pub use cli::Cli;
pub use report::Report;
pub use scenario::Scenario;
pub use world::{Status, run, simulate};
