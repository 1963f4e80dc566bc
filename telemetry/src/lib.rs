//! TauLink's messages and wire formats: what travels over the air between the module and
//! the flight controller. Pure `no_std` code, no radio and no async runtime: the radio
//! driver and the firmware crates plug into it through [`link::PacketRadio`] and
//! [`link::LinkClock`]. What the module speaks to the handset (CRSF, S.Port, FrSky D) is its
//! own crate, `taulink-handset`, re-exported here as [`handset`].
#![cfg_attr(not(any(test, feature = "std")), no_std)]
// docs.rs: the feature each gated item needs, shown beside it.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod change_auth;
pub mod channels;
pub mod checksum;
pub mod cobs;
pub mod frame;
pub mod framing;
/// The handset protocols (CRSF, FrSky S.Port, FrSky D), the `taulink-handset` crate. New
/// code depends on that crate directly; this path stays so existing callers keep building.
pub use taulink_handset as handset;
pub mod link;
pub mod messages;
#[cfg(feature = "std")]
pub mod mock;
pub mod module_record;
pub mod settings;
