//! Packet-level test doubles (feature `std`): a virtual clock with a tiny deterministic
//! executor, and a seeded RF medium with mock radios implementing [`crate::link::PacketRadio`].
//! Link logic tests and the link simulator run both ends on these in virtual time, far faster
//! than real time; the chip-level simulator (`tests/si4432-sim`) is the other, slower rung.

pub mod executor;
pub mod medium;
pub mod radio;

pub use executor::{Executor, MockClock, VirtualTime};
pub use medium::{ChannelModel, Medium, MediumStats, Node};
pub use radio::MockRadio;
pub use sim_rng::SplitMix64;
