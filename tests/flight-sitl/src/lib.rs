//! Software-in-the-loop flight: the flight firmware's own application
//! (`flight_core::app::FlightApp`: flight loop, IMU fault policy, battery monitor, alert
//! player, link hooks and telemetry) driven by simulated task adapters and fed by the
//! TauLink follower, whose channels come over the packet-level
//! mock air from a simulated module master, flying the quad-sim 6-DoF quadrotor — all in one
//! deterministic virtual-time executor. See README.md.
#![warn(missing_docs)]

pub mod console;
pub mod metrics;
mod module_end;
pub mod runner;
pub mod scenario;
pub mod world;

pub use scenario::{
    End, FlashInjection, ImuInjection, Pilot, PilotInput, RadioInjection, Scenario,
};
pub use world::{Boot, BootCause, Sample, Sitl, WatchdogResets, run};
