//! Firmware in the loop: the flight firmware's application (`flight_app::app::FlightApp`)
//! and the module's (`module_core::App`), each driven by simulated adapters of its
//! firmware's tasks, both ends on the real rfm22b driver over virtual Si4432 chips, with
//! independent watchdogs, a settings flash and injectable faults, flying the quad-sim 6-DoF
//! quadrotor — all in si4432-sim's deterministic virtual-time executor. See README.md.
#![warn(missing_docs)]

mod clock;
pub mod console;
mod flash;
pub mod flight_end;
pub mod flight_log;
pub mod gps;
pub mod log_figures;
pub mod metrics;
pub mod module_end;
mod module_flash;
pub mod overlay;
pub mod runner;
pub mod scenario;
pub mod serve;
pub mod ulog_csv;
pub mod world;

pub use scenario::{
    End, FlashInjection, ImuInjection, Pilot, PilotInput, Piloting, RadioInjection, Scenario, Sight,
};
pub use world::{Boot, BootCause, Sample, Sitl, WARMUP_S, WatchdogResets, World, run};
