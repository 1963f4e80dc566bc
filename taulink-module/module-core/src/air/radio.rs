//! The RFM22B driver (`radio-rfm22b`, generic over embedded-hal) as the link's
//! `PacketRadio`: what the firmware's link task runs the link on, and what the chip-level
//! host test runs on the virtual Si4432.
//!
//! ADAPTER: the `link` branch keeps its driver adapter inside the std-only link simulator
//! (`tests/taulink-sim/src/driver.rs`), so the module has its own until one moves into a
//! shared no_std place. Chip setup is the one the link's airtime budget assumes
//! (`telemetry::link::rate`): 40-bit preamble with 20-bit detection, sync 2D D4, the link's
//! four header bytes sent and all 32 bits checked, CRC-CCITT, variable length.

use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;
use radio_rfm22b::{
    Carrier, ChannelSpacing, Config, ConfigError, Crc, ModemConfig, PacketConfig, Rfm22b, TxPower,
};
use telemetry::link::rate::{PREAMBLE_BYTES, airtime_us};
use telemetry::link::{PacketRadio, RadioConfig, RateMode, RxOutcome};

/// Modem of each rate mode. Deviation for a modulation index 2Δf/R of 1.2…3.1 (Tau Labs'
/// and OpenLRSng's profiles span 1.1–4.7, radio.md §1a).
pub fn modem_for(rate: RateMode) -> Result<ModemConfig, ConfigError> {
    let deviation_hz = match rate {
        RateMode::L50 => 30_000,
        RateMode::M100 => 45_000,
        RateMode::F250 => 90_000,
        RateMode::F500 => 150_000,
    };
    ModemConfig::try_new(rate.bit_rate_bps(), deviation_hz)
}

/// Packet handler setup for a link with `header`.
pub fn packet_config(header: [u8; 4]) -> PacketConfig {
    let preamble_nibbles = (PREAMBLE_BYTES * 2) as u16;
    PacketConfig::new()
        .with_preamble(preamble_nibbles, 5)
        .with_sync_word([0x2D, 0xD4, 0, 0], 2)
        .with_header(header, 4)
        .with_header_check(header, [0xFF; 4], 0x0F, 0)
        .with_crc(Crc::Ccitt)
}

/// Why the link's radio failed.
#[derive(Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkRadioError<E> {
    /// The driver failed (bus, chip reset, FIFO).
    Radio(radio_rfm22b::Error<E>),
    /// The link asked for a setup the chip cannot do.
    Config(ConfigError),
}

/// The driver, configured per link phase.
pub struct LinkRadio<SPI, IRQ, SDN, D> {
    radio: Rfm22b<SPI, IRQ, SDN, D>,
    tx_power: TxPower,
    rate: RateMode,
    configured: Option<RadioConfig>,
}

impl<SPI, IRQ, SDN, D> LinkRadio<SPI, IRQ, SDN, D> {
    /// Wraps a driver; `tx_power_step` is the settings' 0…7.
    pub fn new(radio: Rfm22b<SPI, IRQ, SDN, D>, tx_power_step: u8) -> Self {
        Self {
            radio,
            tx_power: TxPower::from_step(tx_power_step),
            rate: RateMode::L50,
            configured: None,
        }
    }

    /// The driver (probe and reset between link sessions).
    pub fn driver(&mut self) -> &mut Rfm22b<SPI, IRQ, SDN, D> {
        // Whoever touches the chip directly invalidates our idea of its setup.
        self.configured = None;
        &mut self.radio
    }
}

impl<SPI, IRQ, SDN, D> PacketRadio for LinkRadio<SPI, IRQ, SDN, D>
where
    SPI: SpiDevice,
    IRQ: Wait,
    SDN: OutputPin,
    D: DelayNs,
{
    type Error = LinkRadioError<SPI::Error>;

    async fn configure(&mut self, config: &RadioConfig) -> Result<(), Self::Error> {
        if self.configured == Some(*config) {
            return Ok(());
        }
        let modem = modem_for(config.rate).map_err(LinkRadioError::Config)?;
        let carrier = Carrier::try_new(config.base_hz).map_err(LinkRadioError::Config)?;
        let mut chip = Config::new(modem, packet_config(config.header), carrier);
        chip.channel_spacing =
            ChannelSpacing::try_from_hz(config.spacing_hz).map_err(LinkRadioError::Config)?;
        chip.tx_power = self.tx_power;
        self.radio.init(chip).await.map_err(LinkRadioError::Radio)?;
        self.rate = config.rate;
        self.configured = Some(*config);
        Ok(())
    }

    async fn set_channel(&mut self, channel: u8) -> Result<(), Self::Error> {
        self.radio
            .set_channel(channel)
            .await
            .map_err(LinkRadioError::Radio)
    }

    async fn transmit(&mut self, frame: &[u8]) -> Result<(), Self::Error> {
        // Twice the airtime plus PLL settling: a chip that has not sent by then is stuck.
        let timeout_us = 2 * airtime_us(frame.len(), self.rate.bit_rate_bps()) + 1_000;
        self.radio
            .transmit(frame, timeout_us)
            .await
            .map_err(LinkRadioError::Radio)
    }

    async fn receive(&mut self, buf: &mut [u8], timeout_us: u32) -> Result<RxOutcome, Self::Error> {
        let outcome = self
            .radio
            .receive(buf, timeout_us)
            .await
            .map_err(LinkRadioError::Radio)?;
        Ok(match outcome {
            radio_rfm22b::RxOutcome::Packet(packet) => RxOutcome::Packet {
                len: packet.len,
                rssi_dbm: packet.signal.rssi_dbm,
            },
            radio_rfm22b::RxOutcome::CrcError(_) | radio_rfm22b::RxOutcome::TooLong { .. } => {
                RxOutcome::Corrupted
            }
            radio_rfm22b::RxOutcome::Timeout => RxOutcome::Timeout,
        })
    }
}
