//! The driver as the TauLink air link's radio (`telemetry::link::PacketRadio`), behind the
//! `telemetry` feature: one adapter for the module firmware, the flight firmware and the
//! host simulations, so they all run the link on the same chip setup.
//!
//! The chip setup is what the link's airtime budget (`telemetry::link::rate`) assumes:
//! preamble of `PREAMBLE_BYTES` with 20-bit detection, sync `2D D4`, the link's four header
//! bytes sent and all 32 bits checked (none at F700, `RateMode::chip_header_bytes`: the
//! keyed link CRC identifies its packets), CRC-CCITT, variable length.

use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;
use telemetry::link::rate::PREAMBLE_BYTES;
use telemetry::link::{LinkRx, PacketRadio, RadioConfig, RateMode};

use crate::{
    Carrier, ChannelSpacing, Config, ConfigError, Crc, Error, ModemConfig, PacketConfig, Rfm22b,
    TxPower,
};

/// The link's clock on embassy-time (feature `embassy-time`): its ticks in µs as the time,
/// `Timer::at` as the sleep — the one both TauLink firmwares run their link loops on (and
/// the module's JR-line task stamps its CRSF frames with, so slot times are directly the
/// CRSF timing frame's phase).
#[cfg(feature = "embassy-time")]
#[cfg_attr(docsrs, doc(cfg(feature = "embassy-time")))]
#[derive(Clone, Copy, Debug, Default)]
pub struct EmbassyClock;

#[cfg(feature = "embassy-time")]
impl telemetry::link::LinkClock for EmbassyClock {
    fn now_us(&self) -> u64 {
        embassy_time::Instant::now().as_micros()
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        embassy_time::Timer::at(embassy_time::Instant::from_micros(deadline_us)).await;
    }
}

/// The modem of each rate mode: deviation for a modulation index 2Δf/R of 1.2…3.1 (Tau
/// Labs' and OpenLRSng's profiles span 1.1–4.7); 256 kbps uses the 150 kHz Tau Labs
/// intended, not its table's 9.4 kHz typo.
pub const fn modem_for(rate: RateMode) -> Result<ModemConfig, ConfigError> {
    let deviation_hz = match rate {
        RateMode::L50 => 30_000,
        RateMode::M100 => 45_000,
        RateMode::F250 => 90_000,
        RateMode::F500 | RateMode::F700 => 150_000,
    };
    ModemConfig::try_new(rate.bit_rate_bps(), deviation_hz)
}

/// The packet handler for a link with `header`; `check_header` = false turns the hardware
/// header filter off (a test mode that exposes foreign packets to the link CRC).
pub fn packet_config(header: [u8; 4], check_header: bool) -> PacketConfig {
    let nibbles = (PREAMBLE_BYTES * 2) as u16;
    let checked = if check_header { 0x0F } else { 0x00 };
    PacketConfig::new()
        .with_preamble(nibbles, 5)
        .with_sync_word([0x2D, 0xD4, 0, 0], 2)
        .with_header(header, 4)
        .with_header_check(header, [0xFF; 4], checked, 0)
        .with_crc(Crc::Ccitt)
}

/// The packet handler for a link at `rate`: [`packet_config`], or without any hardware
/// header where the mode sends none (`RateMode::chip_header_bytes`, F700: the keyed link
/// CRC is its identity check).
pub fn packet_config_for(rate: RateMode, header: [u8; 4], check_header: bool) -> PacketConfig {
    if rate.chip_header_bytes() == 0 {
        let nibbles = (PREAMBLE_BYTES * 2) as u16;
        PacketConfig::new()
            .with_preamble(nibbles, 5)
            .with_sync_word([0x2D, 0xD4, 0, 0], 2)
            .with_crc(Crc::Ccitt)
    } else {
        packet_config(header, check_header)
    }
}

/// Why the link's radio failed.
#[derive(Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkRadioError<E> {
    /// The driver failed (bus, chip reset, FIFO).
    Radio(Error<E>),
    /// The link asked for a setup the chip cannot do.
    Config(ConfigError),
}

/// The driver, configured per link phase (bind, then the bound link).
pub struct LinkRadio<SPI, IRQ, SDN, D> {
    radio: Rfm22b<SPI, IRQ, SDN, D>,
    tx_power: TxPower,
    check_header: bool,
    rate: RateMode,
    configured: Option<RadioConfig>,
}

impl<SPI, IRQ, SDN, D> LinkRadio<SPI, IRQ, SDN, D> {
    /// Wraps a driver, transmitting at `tx_power` (bind mode: [`TxPower::MIN`]), with the
    /// header filter on.
    pub fn new(radio: Rfm22b<SPI, IRQ, SDN, D>, tx_power: TxPower) -> Self {
        Self {
            radio,
            tx_power,
            check_header: true,
            rate: RateMode::L50,
            configured: None,
        }
    }

    /// Turns the hardware header filter off (tests of the link CRC against foreign links).
    pub fn without_header_check(mut self) -> Self {
        self.check_header = false;
        self
    }

    /// Gives the driver back (to run the chip another way, e.g. the OpenLRSng roles over its
    /// parts, `Rfm22b::release`).
    pub fn release(self) -> Rfm22b<SPI, IRQ, SDN, D> {
        self.radio
    }

    /// The driver itself (probe and reset between link sessions).
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
        // Each mode's modem computed at build time: the register calculator's arithmetic
        // stays out of the image (issue 33).
        let modem = match config.rate {
            RateMode::L50 => const { modem_for(RateMode::L50) },
            RateMode::M100 => const { modem_for(RateMode::M100) },
            RateMode::F250 => const { modem_for(RateMode::F250) },
            RateMode::F500 => const { modem_for(RateMode::F500) },
            RateMode::F700 => const { modem_for(RateMode::F700) },
        }
        .map_err(LinkRadioError::Config)?;
        let carrier = Carrier::try_new(config.base_hz).map_err(LinkRadioError::Config)?;
        let mut chip = Config::new(
            modem,
            packet_config_for(config.rate, config.header, self.check_header),
            carrier,
        );
        chip.channel_spacing =
            ChannelSpacing::try_from_hz(config.spacing_hz).map_err(LinkRadioError::Config)?;
        // Bind mode transmits at the lowest step whatever the link's power: binding is a
        // close-range act, and a bind nobody nearby can hear cannot be overheard either.
        chip.tx_power = if config.reduced_power {
            TxPower::MIN
        } else {
            self.tx_power
        };
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
        // Twice the airtime plus the PLL settle: a chip that has not sent by then is stuck.
        let timeout_us = 2 * self.rate.airtime_us(frame.len()) + 1_000;
        self.radio
            .transmit(frame, timeout_us)
            .await
            .map_err(LinkRadioError::Radio)
    }

    async fn begin_transmit(&mut self, len: usize) -> Result<(), Self::Error> {
        self.radio
            .begin_transmit(len)
            .await
            .map_err(LinkRadioError::Radio)
    }

    async fn finish_transmit(&mut self, frame: &[u8]) -> Result<(), Self::Error> {
        // As `transmit`: twice the airtime plus the PLL settle.
        let timeout_us = 2 * self.rate.airtime_us(frame.len()) + 1_000;
        self.radio
            .finish_transmit(frame, timeout_us)
            .await
            .map_err(LinkRadioError::Radio)
    }

    async fn receive(&mut self, buf: &mut [u8], timeout_us: u32) -> Result<LinkRx, Self::Error> {
        let outcome = self
            .radio
            .receive(buf, timeout_us)
            .await
            .map_err(LinkRadioError::Radio)?;
        Ok(match outcome {
            crate::RxOutcome::Packet(packet) => LinkRx::Packet {
                len: packet.len,
                rssi_dbm: packet.signal.rssi_dbm,
            },
            crate::RxOutcome::CrcError(_) | crate::RxOutcome::TooLong { .. } => LinkRx::Corrupted,
            crate::RxOutcome::Timeout => LinkRx::Timeout,
        })
    }

    /// Register 0x6D at `step` (the driver's [`Rfm22b::set_tx_power`]); kept for every later
    /// (re)configuration of the bound link.
    async fn set_tx_power(&mut self, step: u8) -> Result<(), Self::Error> {
        self.tx_power = TxPower::from_step(step);
        // In bind mode the chip stays at its lowest step: only the bound link's power moves.
        if self.configured.is_some_and(|c| c.reduced_power) {
            return Ok(());
        }
        self.radio
            .set_tx_power(self.tx_power)
            .await
            .map_err(LinkRadioError::Radio)
    }

    /// The driver's [`Rfm22b::check_health`]: a chip that lost its setup (silent reset) is
    /// re-initialised and reported as [`Error::ChipReset`].
    async fn check_health(&mut self) -> Result<(), Self::Error> {
        self.radio
            .check_health()
            .await
            .map_err(LinkRadioError::Radio)
    }

    /// Forgets the cached setup and initialises the chip again (reset, registers, modem).
    async fn recover(&mut self, config: &RadioConfig) -> Result<(), Self::Error> {
        self.configured = None;
        self.configure(config).await
    }
}
