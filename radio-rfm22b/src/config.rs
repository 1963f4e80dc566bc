//! Everything the driver programs once at `init`: modem, packet handler, carrier and hop
//! spacing, power, crystal, GPIOs, FIFO thresholds.

use crate::ConfigError;
use crate::carrier::{Carrier, ChannelSpacing};
use crate::fifo::FifoThresholds;
use crate::gpio::GpioConfig;
use crate::modem::ModemConfig;
use crate::packet::PacketConfig;
use crate::power::{CrystalLoad, TxPower};

/// The complete radio configuration. Build with [`Config::new`] and adjust the public fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Modem registers (bit rate, deviation, filters, AFC).
    pub modem: ModemConfig,
    /// Packet handler.
    pub packet: PacketConfig,
    /// Carrier of hop channel 0.
    pub carrier: Carrier,
    /// Hop channel spacing (0x7A).
    pub channel_spacing: ChannelSpacing,
    /// Output power.
    pub tx_power: TxPower,
    /// Set 0x6D `lna_sw` (Tau Labs does; OpenLRSng does not).
    pub lna_switch: bool,
    /// Crystal load trim.
    pub crystal_load: CrystalLoad,
    /// GPIO functions and antenna-switch wiring.
    pub gpio: GpioConfig,
    /// FIFO thresholds for packets longer than 64 bytes.
    pub fifo: FifoThresholds,
    /// Clear-channel threshold for GPIO2's CCA output (0x27), in dBm.
    pub clear_channel_threshold_dbm: i16,
}

impl Config {
    /// `modem`, `packet` and `carrier` with: 10 kHz hop spacing, +20 dBm with `lna_sw`,
    /// crystal load 0x7F, Tau Labs GPIO wiring, 62/32/32 FIFO thresholds, CCA at −90 dBm.
    pub const fn new(modem: ModemConfig, packet: PacketConfig, carrier: Carrier) -> Self {
        Self {
            modem,
            packet,
            carrier,
            channel_spacing: ChannelSpacing::from_10khz_steps(1),
            tx_power: TxPower::MAX,
            lna_switch: true,
            crystal_load: CrystalLoad::RFM22B,
            gpio: GpioConfig::RFM22B,
            fifo: FifoThresholds::HALF,
            clear_channel_threshold_dbm: -90,
        }
    }

    /// Checks the parts that are not validated at their own construction.
    pub const fn validate(&self) -> Result<(), ConfigError> {
        if let Err(e) = self.packet.validate() {
            return Err(e);
        }
        self.fifo.validate()
    }
}
