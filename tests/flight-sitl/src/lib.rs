//! Software-in-the-loop flight: the flight controller's logic exactly as the firmware runs it
//! (settings → `pipeline::from_settings` → `FlightLoop`, battery monitor, alert player,
//! telemetry reports) fed by the TauLink follower, whose channels come over the packet-level
//! mock air from a simulated module master, flying the quad-sim 6-DoF quadrotor — all in one
//! deterministic virtual-time executor. See README.md.
#![warn(missing_docs)]

pub mod console;
mod link_ends;
pub mod metrics;
pub mod scenario;
pub mod world;

pub use scenario::{Pilot, PilotInput, Scenario};
pub use world::{Sample, Sitl, run};
