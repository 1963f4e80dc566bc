//! The link's view of the hardware: `telemetry::link::PacketRadio` on the RFM22B driver and
//! `LinkClock` on embassy-time. Per rate mode the modem runs the protocol's bit rate with a
//! deviation giving a modulation index 2Δf/R of 1.2–3.1 (radio.md §1a); the packet handler
//! sends a 40-bit preamble, sync 2D D4, the link's four header bytes (all checked by the
//! chip) and CRC-CCITT — the overhead `telemetry::link::rate` budgets for.

use embassy_time::{Instant, Timer};
use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;
use radio_rfm22b::{Carrier, ChannelSpacing, Config, Crc, ModemConfig, PacketConfig, Rfm22b};
use telemetry::link::rate::{PREAMBLE_BYTES, airtime_us};
use telemetry::link::{LinkClock, PacketRadio, RadioConfig, RateMode, RxOutcome};

/// Frequency deviation per rate mode, Hz.
const fn deviation_hz(rate: RateMode) -> u32 {
    match rate {
        RateMode::L50 => 30_000,
        RateMode::M100 => 45_000,
        RateMode::F250 => 90_000,
        RateMode::F500 => 150_000,
    }
}

/// Why the radio failed.
#[derive(Debug)]
pub enum LinkRadioError<E: core::fmt::Debug> {
    /// The driver (bus, chip) failed.
    Radio(radio_rfm22b::Error<E>),
    /// The link asked for something the chip cannot do.
    Config(radio_rfm22b::ConfigError),
}

/// The RFM22B as the link's packet radio.
pub struct LinkRadio<SPI, IRQ, SDN, D> {
    chip: Rfm22b<SPI, IRQ, SDN, D>,
    rate: RateMode,
    loaded: Option<RadioConfig>,
}

impl<E: core::fmt::Debug> defmt::Format for LinkRadioError<E> {
    fn format(&self, f: defmt::Formatter<'_>) {
        match self {
            LinkRadioError::Radio(e) => defmt::write!(f, "radio: {}", defmt::Debug2Format(e)),
            LinkRadioError::Config(e) => defmt::write!(f, "config: {}", defmt::Debug2Format(e)),
        }
    }
}

impl<SPI, IRQ, SDN, D> LinkRadio<SPI, IRQ, SDN, D> {
    /// Wraps the driver; nothing is configured until the link asks.
    pub fn new(chip: Rfm22b<SPI, IRQ, SDN, D>) -> Self {
        Self {
            chip,
            rate: RateMode::L50,
            loaded: None,
        }
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
        if self.loaded == Some(*config) {
            return Ok(());
        }
        let modem = ModemConfig::try_new(config.rate.bit_rate_bps(), deviation_hz(config.rate))
            .map_err(LinkRadioError::Config)?;
        let carrier = Carrier::try_new(config.base_hz).map_err(LinkRadioError::Config)?;
        let preamble_nibbles = (PREAMBLE_BYTES * 2) as u16;
        let packet = PacketConfig::new()
            .with_preamble(preamble_nibbles, 5)
            .with_sync_word([0x2D, 0xD4, 0, 0], 2)
            .with_header(config.header, 4)
            .with_header_check(config.header, [0xFF; 4], 0x0F, 0)
            .with_crc(Crc::Ccitt);
        let mut chip = Config::new(modem, packet, carrier);
        chip.channel_spacing =
            ChannelSpacing::try_from_hz(config.spacing_hz).map_err(LinkRadioError::Config)?;
        self.chip.init(chip).await.map_err(LinkRadioError::Radio)?;
        self.rate = config.rate;
        self.loaded = Some(*config);
        Ok(())
    }

    async fn set_channel(&mut self, channel: u8) -> Result<(), Self::Error> {
        self.chip
            .set_channel(channel)
            .await
            .map_err(LinkRadioError::Radio)
    }

    async fn transmit(&mut self, frame: &[u8]) -> Result<(), Self::Error> {
        // A packet not gone after twice its airtime plus the PLL settle means a stuck chip.
        let timeout_us = 2 * airtime_us(frame.len(), self.rate.bit_rate_bps()) + 1_000;
        self.chip
            .transmit(frame, timeout_us)
            .await
            .map_err(LinkRadioError::Radio)
    }

    async fn receive(&mut self, buf: &mut [u8], timeout_us: u32) -> Result<RxOutcome, Self::Error> {
        let outcome = self
            .chip
            .receive(buf, timeout_us)
            .await
            .map_err(LinkRadioError::Radio)?;
        Ok(match outcome {
            radio_rfm22b::RxOutcome::Packet(p) => RxOutcome::Packet {
                len: p.len,
                rssi_dbm: p.signal.rssi_dbm,
            },
            radio_rfm22b::RxOutcome::CrcError(_) | radio_rfm22b::RxOutcome::TooLong { .. } => {
                RxOutcome::Corrupted
            }
            radio_rfm22b::RxOutcome::Timeout => RxOutcome::Timeout,
        })
    }
}

/// The link's clock: embassy-time's 1 MHz tick.
pub struct EmbassyClock;

impl LinkClock for EmbassyClock {
    fn now_us(&self) -> u64 {
        Instant::now().as_micros()
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        Timer::at(Instant::from_micros(deadline_us)).await;
    }
}
