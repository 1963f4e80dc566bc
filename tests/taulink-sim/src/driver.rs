//! `PacketRadio` for the real RFM22b driver, and `LinkClock` for the chip simulator's
//! virtual time: the glue that puts the link code on `radio-rfm22b` over `si4432-sim`.
//! (Kept here, not behind a driver feature, until the driver's owners adopt it.)

use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;
use radio_rfm22b::{Carrier, ChannelSpacing, Config, Crc, ModemConfig, PacketConfig, Rfm22b};
use si4432_sim::{Medium, SimDelay};
use telemetry::link::rate::{PREAMBLE_BYTES, airtime_us};
use telemetry::link::{LinkClock, PacketRadio, RadioConfig, RateMode, RxOutcome};

/// The modem of each rate mode: bit rate and deviation. Modulation index 2Δf/R between 1.2
/// and 3.1 (Tau Labs' and OpenLRSng's profiles use 1.1–4.7); 256 kbps uses the 150 kHz
/// Tau Labs intended (its table's 9.4 kHz is the bug noted in radio.md §1a).
pub fn modem_for(rate: RateMode) -> Result<ModemConfig, radio_rfm22b::ConfigError> {
    let deviation_hz = match rate {
        RateMode::L50 => 30_000,
        RateMode::M100 => 45_000,
        RateMode::F250 => 90_000,
        RateMode::F500 => 150_000,
    };
    ModemConfig::try_new(rate.bit_rate_bps(), deviation_hz)
}

/// The packet handler for a link: 40-bit preamble (20-bit detection), sync `2D D4`, the
/// link's 4 header bytes sent and all 32 bits checked (no broadcast), CRC-CCITT, variable
/// length — exactly the overhead `telemetry::link::rate` budgets for.
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

/// Errors of the adapter.
#[derive(Debug)]
pub enum DriverError<E> {
    /// The driver failed.
    Radio(radio_rfm22b::Error<E>),
    /// The link asked for a configuration the chip cannot do.
    Config(radio_rfm22b::ConfigError),
}

/// The RFM22b driver as a link radio.
pub struct DriverRadio<SPI, IRQ, SDN, D> {
    radio: Rfm22b<SPI, IRQ, SDN, D>,
    rate: RateMode,
    check_header: bool,
    configured: Option<RadioConfig>,
}

impl<SPI, IRQ, SDN, D> DriverRadio<SPI, IRQ, SDN, D> {
    /// Wraps a driver; `check_header` = false turns the hardware header filter off (a test
    /// mode that exposes foreign packets to the link CRC).
    pub fn new(radio: Rfm22b<SPI, IRQ, SDN, D>, check_header: bool) -> Self {
        Self {
            radio,
            rate: RateMode::L50,
            check_header,
            configured: None,
        }
    }
}

impl<SPI, IRQ, SDN, D> PacketRadio for DriverRadio<SPI, IRQ, SDN, D>
where
    SPI: SpiDevice,
    IRQ: Wait,
    SDN: OutputPin,
    D: DelayNs,
{
    type Error = DriverError<SPI::Error>;

    async fn configure(&mut self, config: &RadioConfig) -> Result<(), Self::Error> {
        if self.configured == Some(*config) {
            return Ok(());
        }
        let modem = modem_for(config.rate).map_err(DriverError::Config)?;
        let carrier = Carrier::try_new(config.base_hz).map_err(DriverError::Config)?;
        let mut chip = Config::new(
            modem,
            packet_config(config.header, self.check_header),
            carrier,
        );
        chip.channel_spacing =
            ChannelSpacing::try_from_hz(config.spacing_hz).map_err(DriverError::Config)?;
        self.radio.init(chip).await.map_err(DriverError::Radio)?;
        self.rate = config.rate;
        self.configured = Some(*config);
        Ok(())
    }

    async fn set_channel(&mut self, channel: u8) -> Result<(), Self::Error> {
        self.radio
            .set_channel(channel)
            .await
            .map_err(DriverError::Radio)
    }

    async fn transmit(&mut self, frame: &[u8]) -> Result<(), Self::Error> {
        // Twice the airtime plus the PLL settle: a chip that has not sent by then is stuck.
        let timeout = 2 * airtime_us(frame.len(), self.rate.bit_rate_bps()) + 1_000;
        self.radio
            .transmit(frame, timeout)
            .await
            .map_err(DriverError::Radio)
    }

    async fn receive(&mut self, buf: &mut [u8], timeout_us: u32) -> Result<RxOutcome, Self::Error> {
        Ok(
            match self
                .radio
                .receive(buf, timeout_us)
                .await
                .map_err(DriverError::Radio)?
            {
                radio_rfm22b::RxOutcome::Packet(p) => RxOutcome::Packet {
                    len: p.len,
                    rssi_dbm: p.signal.rssi_dbm,
                },
                radio_rfm22b::RxOutcome::CrcError(_) | radio_rfm22b::RxOutcome::TooLong { .. } => {
                    RxOutcome::Corrupted
                }
                radio_rfm22b::RxOutcome::Timeout => RxOutcome::Timeout,
            },
        )
    }
}

/// A link clock on the chip simulator's virtual time, offset like a separately booted MCU
/// and running `drift_ppm` fast or slow like its crystal.
#[derive(Clone)]
pub struct SimClock {
    medium: Medium,
    delay: SimDelay,
    offset_us: u64,
    drift_ppm: f64,
}

impl SimClock {
    /// A clock reading (virtual time × (1 + drift_ppm·10⁻⁶)) + `offset_us`.
    pub fn new(medium: Medium, delay: SimDelay, offset_us: u64, drift_ppm: f64) -> Self {
        Self {
            medium,
            delay,
            offset_us,
            drift_ppm,
        }
    }

    /// Virtual time without offset or drift (the common reference for measurements).
    pub fn virtual_us(&self) -> u64 {
        self.medium.now().as_micros() as u64
    }
}

impl LinkClock for SimClock {
    fn now_us(&self) -> u64 {
        let v = self.medium.now().as_nanos() as f64 / 1e3;
        (v * (1.0 + self.drift_ppm * 1e-6)) as u64 + self.offset_us
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        let local_wait_us = deadline_us.saturating_sub(self.now_us());
        if local_wait_us > 0 {
            // Local microseconds → virtual nanoseconds, rounded up so we never wake early.
            let virtual_ns =
                (local_wait_us as f64 * 1e3 / (1.0 + self.drift_ppm * 1e-6)).ceil() as u64;
            self.delay.sleep_ns(virtual_ns).await;
        }
    }
}
