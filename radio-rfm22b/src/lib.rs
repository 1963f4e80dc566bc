//! Driver for the Silicon Labs Si4432 (HopeRF RFM22B) sub-GHz transceiver.
//!
//! `no_std`, generic over embedded-hal 1.0 (`OutputPin`) and embedded-hal-async
//! (`SpiDevice`, `Wait`, `DelayNs`); it knows nothing of embassy, so it runs on any HAL, on a
//! Linux spidev, or against the virtual Si4432 in `tests/si4432-sim`.
//!
//! Configure once, then per slot set the channel and transmit or receive:
//!
//! ```
//! use radio_rfm22b::{Carrier, Config, Error, ModemConfig, PacketConfig, Rfm22b, RxOutcome};
//!
//! /// Checked when compiling: an impossible modem setting does not build.
//! const MODEM: ModemConfig = ModemConfig::new(57_600, 28_800);
//!
//! async fn one_slot<SPI, IRQ, SDN, D>(
//!     radio: &mut Rfm22b<SPI, IRQ, SDN, D>,
//! ) -> Result<(), Error<SPI::Error>>
//! where
//!     SPI: embedded_hal_async::spi::SpiDevice,
//!     IRQ: embedded_hal_async::digital::Wait,
//!     SDN: embedded_hal::digital::OutputPin,
//!     D: embedded_hal_async::delay::DelayNs,
//! {
//!     radio
//!         .init(Config::new(MODEM, PacketConfig::new(), Carrier::new(433_000_000)))
//!         .await?;
//!     radio.set_channel(7).await?;
//!     radio.transmit(b"hello", 10_000).await?;
//!     let mut buf = [0u8; 255];
//!     match radio.receive(&mut buf, 20_000).await? {
//!         RxOutcome::Packet(p) => {
//!             let _payload = &buf[..p.len];
//!             let _quality = (p.signal.rssi_dbm, p.signal.afc_offset_hz);
//!         }
//!         RxOutcome::CrcError(_) | RxOutcome::TooLong { .. } | RxOutcome::Timeout => {}
//!     }
//!     Ok(())
//! }
//! ```
#![cfg_attr(not(test), no_std)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(unsafe_code)]
#![warn(missing_docs)]

// `rfm22b` first: rustdoc lists `Rfm22b`'s methods in module order, constructors first.
mod rfm22b;
mod bus;
pub mod carrier;
mod config;
mod config_error;
mod control;
mod error;
pub mod fifo;
pub mod gpio;
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
