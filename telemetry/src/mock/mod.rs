//! Packet-level test doubles (feature `std`): a seeded RF medium with mock radios
//! implementing [`crate::link::PacketRadio`], on the simulators' one executor, virtual time
//! and board clock (`sim-exec`, re-exported here; [`SimClock`] is a [`crate::link::LinkClock`]).
//! Link logic tests and the link simulator run both ends on these in virtual time, far faster
//! than real time; the chip-level simulator (`tests/si4432-sim`) is the other, slower rung,
//! on the same executor and clock.
//!
//! The mock radio's futures check the medium when polled rather than registering wakers: the
//! medium and the radio ask for a wake-up of every task ([`VirtualTime::wake_all_at`]) at each
//! packet end and receive deadline.

mod clock;
pub mod medium;
pub mod radio;

pub use medium::{ChannelModel, Medium, MediumStats, Node};
pub use radio::MockRadio;
pub use sim_exec::{Executor, SimClock, Sleep, Spawner, Task, VirtualTime};
pub use sim_rng::SplitMix64;
