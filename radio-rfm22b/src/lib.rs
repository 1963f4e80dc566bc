// The README is the front page. Its `[guide]` links point at `src/guide.md` for readers of
// the repository; the definition put first here wins in rustdoc and makes them intra-doc links.
#![doc = concat!("[guide]: crate::guide\n\n", include_str!("../README.md"))]
#![cfg_attr(not(test), no_std)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(unsafe_code)]
#![warn(missing_docs)]

// `rfm22b` first: rustdoc lists `Rfm22b`'s methods in module order, constructors first.
mod bus;
pub mod carrier;
mod config;
mod config_error;
mod control;
#[cfg(all(feature = "telemetry", feature = "openlrs"))]
#[cfg_attr(docsrs, doc(cfg(all(feature = "telemetry", feature = "openlrs"))))]
pub mod dual;
mod error;
pub mod fifo;
pub mod gpio;
pub mod guide;
pub mod if_filter;
pub mod irq;
#[cfg(feature = "telemetry")]
#[cfg_attr(docsrs, doc(cfg(feature = "telemetry")))]
pub mod link;
#[cfg(feature = "linux")]
#[cfg_attr(docsrs, doc(cfg(feature = "linux")))]
pub mod linux;
pub mod measure;
pub mod modem;
#[cfg(feature = "openlrs")]
#[cfg_attr(docsrs, doc(cfg(feature = "openlrs")))]
pub mod openlrs;
pub mod packet;
pub mod power;
mod probe;
pub mod registers;
mod rfm22b;
mod rx;
mod tx;

pub use bus::Bus;
pub use carrier::{Carrier, ChannelSpacing};
pub use config::Config;
pub use config_error::ConfigError;
pub use error::Error;
pub use gpio::{AntennaSwitch, Gpio2, GpioConfig};
pub use if_filter::IfFilter;
pub use modem::{ModemConfig, ModemSettings, Modulation};
pub use packet::{Crc, PacketConfig, PacketLength};
pub use power::{CrystalLoad, TxPower};
pub use probe::{ChipInfo, Version};
pub use rfm22b::{NoPin, Rfm22b};
pub use rx::{RxOutcome, RxPacket, RxSignal};
