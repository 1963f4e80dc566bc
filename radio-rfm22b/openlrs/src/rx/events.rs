//! What crosses the receiver's boundary: its settings, the commands it gives the radio, and
//! what it reports for each packet and each timer tick.

use heapless::Vec;

use crate::RfmType;
use crate::bind::{BindData, BindReception};
use crate::channels::MAX_CHANNELS;
use crate::telemetry;
use crate::uplink::Uplink;
use crate::version::BindingVersion;

/// Receiver settings (the parts of OpenLRSng's `rx_config` the link logic uses).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Generation to bind with; bind packets of the other one are refused.
    pub version: BindingVersion,
    /// Module band (binding frequency).
    pub band: RfmType,
    /// `failsafeDelay` in `delayInMs` code (default 10 = 1 s); 0 never applies failsafe.
    pub failsafe_delay: u8,
    /// Bind listening at boot when already bound (`ALWAYS_BIND`: 500 ms); `None` skips it.
    pub bind_window_us: Option<u32>,
}

impl Config {
    /// OpenLRSng's defaults: failsafe after 1 s, a 500 ms bind window at boot.
    pub const fn new(version: BindingVersion, band: RfmType) -> Self {
        Self {
            version,
            band,
            failsafe_delay: 10,
            bind_window_us: Some(500_000),
        }
    }
}

/// What the radio must do next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Program the bind configuration (`init_rfm(1)`) and listen.
    ListenBind,
    /// Program the link configuration (`init_rfm(0)`), tune hop index 0 and listen.
    StartLink(BindData),
    /// Tune this hop index (0x79 and the header byte) and listen again.
    Hop(u8),
}

/// What the application gets from a received packet.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Output {
    /// Nothing new (a repeated serial packet, an ignored bind-channel packet).
    Nothing,
    /// New bind data: persist it; the link starts with it.
    Bound(BindData),
    /// A bind packet that this RX refuses.
    BindRefused(BindReception),
    /// Channel values (10-bit). `save_failsafe` is set once per TX button press.
    Channels {
        /// `mode.channel_count()` values.
        channels_bits: Vec<u16, MAX_CHANNELS>,
        /// Store these values as failsafe.
        save_failsafe: bool,
    },
    /// New serial bytes for the RX UART.
    Serial(Vec<u8, 8>),
    /// A packet of a type we do not handle.
    Unknown(Uplink),
}

/// The RX's answer to one packet.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Reception {
    /// Send this now, on the same channel (the `'B'` ack or a 9-byte telemetry frame).
    pub reply: Option<Vec<u8, { telemetry::DOWNLINK_FRAME_LEN }>>,
    /// Then do this (after the reply has gone).
    pub command: Option<Command>,
    /// For the application.
    pub output: Output,
}

/// What a timer tick changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tick {
    /// Radio command, if any.
    pub command: Option<Command>,
    /// Failsafe has just started: apply the stored failsafe values.
    pub failsafe_started: bool,
    /// Read RSSI (0x26) now and pass it to [`Receiver::on_rssi_sample`](super::Receiver::on_rssi_sample): the next packet
    /// should be on air.
    pub sample_rssi: bool,
}
