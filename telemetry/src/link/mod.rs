//! The TauLink air protocol: rate modes, hopping, slot schedule, reliable stream, link
//! quality and bind — each a small pure module — plus the pure master/follower state
//! machines (`core`) and the thin async loops that drive them over a [`PacketRadio`].
//! Wire format and timing: `spec/protocol.md`.

pub mod alarm;
pub mod auth;
pub mod bind;
pub mod core;
pub mod entropy;
pub mod follower;
pub mod hopping;
pub mod master;
pub mod pake;
pub mod phrase;
pub mod power;
pub mod quality;
pub mod radio;
pub mod rate;
mod recovery;
pub mod schedule;
mod sha512;
mod step_io;
pub mod stream;

pub use auth::{Fingerprint, LinkKey};
pub use bind::{BIND_HEADER, BIND_KEY, BindAuth, BindRefusal, FollowerAuth, LinkParams};
pub use entropy::Entropy;
pub use hopping::{Band, HOP_CHANNELS, HopSequence};
pub use phrase::{PhraseError, PhraseSecret, check_phrase};
pub use radio::{LinkClock, LinkRx, PacketRadio, RadioConfig};
pub use rate::{RateMode, UnknownRateMode};
pub use schedule::{Schedule, SlotKind};
