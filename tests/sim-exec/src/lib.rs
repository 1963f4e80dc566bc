//! The one deterministic executor, virtual time and simulated board clock of every
//! simulation in the workspace: the packet-level mock (`telemetry::mock`, the link tests, the
//! link simulator's packet world) and the chip-level world (`si4432-sim`'s `Simulation`,
//! flight-sitl, the link simulator's chip world) run on these same definitions.
//!
//! - [`VirtualTime`] (ns): the current instant and a heap of wake-ups; [`Sleep`] futures.
//!   Nothing real ever sleeps, and idle time costs nothing.
//! - [`Executor`]: single-threaded, polls tasks with real wakers in a fixed order, then moves
//!   time to the earliest wake-up, or to the earliest event of an attached world
//!   ([`Events`]: si4432-sim's chips), so the same tasks and seed give the same trace.
//!   [`Spawner`] spawns from inside tasks; [`Task`] is a spawned task's result.
//! - [`SimClock`]: a board's clock on that time — its own epoch and a crystal `drift_ppm`
//!   off (with `telemetry`'s `std` feature it is the link's `LinkClock`).
//!
//! No dependencies, no global state, no threads.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod clock;
mod executor;
mod time;

pub use clock::SimClock;
pub use executor::{Executor, Spawner, Task};
pub use time::{Events, Sleep, VirtualTime};

/// The README's examples, run as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
