//! The driver: `Rfm22b` owns the SPI device, nIRQ, SDN and a delay. This file holds
//! construction, reset/probe, configuration and the end-of-operation clean-up; run-time
//! controls live in `control.rs`, TX and RX in `tx.rs` and `rx.rs`.

use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;

use crate::Error;
use crate::bus::Bus;
use crate::config::Config;
use crate::irq::Status;
use crate::measure;
use crate::probe::ChipInfo;
use crate::registers::*;

/// Polls of the chip-ready flag after a software reset, 1 ms apart (Tau Labs: 50).
const CHIP_READY_POLLS: u32 = 50;
/// SDN high long enough to discharge the chip (≥ 10 ms, with margin).
const SDN_HIGH_MS: u32 = 15;
/// Power-on reset after SDN falls: up to 16.8 ms (datasheet), rounded up.
const SDN_LOW_MS: u32 = 20;

/// A stand-in for an SDN pin on boards that tie SDN low.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoPin;

impl embedded_hal::digital::ErrorType for NoPin {
    type Error = core::convert::Infallible;
}

impl OutputPin for NoPin {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// The Si4432 / RFM22B driver.
///
/// Configure once with [`Rfm22b::init`], then per slot: [`Rfm22b::set_channel`] →
/// [`Rfm22b::transmit`] or [`Rfm22b::receive`].
pub struct Rfm22b<SPI, IRQ, SDN, D> {
    pub(crate) bus: Bus<SPI>,
    pub(crate) irq: IRQ,
    sdn: SDN,
    sdn_present: bool,
    pub(crate) delay: D,
    pub(crate) config: Option<Config>,
    pub(crate) channel: u8,
    /// An operation left the chip in TX/RX with interrupts enabled (it was cancelled).
    pub(crate) busy: bool,
    /// The chip is in standby: the next TX/RX will see a (legitimate) chip-ready flag.
    pub(crate) standby: bool,
    /// A packet begun with [`Rfm22b::begin_transmit`]: its length, and whether the chip
    /// came out of standby for it.
    pub(crate) begun: Option<(usize, bool)>,
}

// Constructors first (rustdoc lists methods in this order); they need no trait bounds.
impl<SPI, IRQ, SDN, D> Rfm22b<SPI, IRQ, SDN, D> {
    /// A driver for a chip whose SDN pin the MCU drives (hard reset possible).
    pub fn new(spi: SPI, irq: IRQ, sdn: SDN, delay: D) -> Self {
        Self::from_parts(spi, irq, sdn, true, delay)
    }

    /// A driver over `sdn`, which is a real pin only when `sdn_present` (else the
    /// `new_without_sdn` behaviour): for adapters that take a driver apart with
    /// [`Rfm22b::release`] and rebuild it (the OpenLRSng crate's `DualRadio`).
    pub fn from_parts(spi: SPI, irq: IRQ, sdn: SDN, sdn_present: bool, delay: D) -> Self {
        Self {
            bus: Bus::new(spi),
            irq,
            sdn,
            sdn_present,
            delay,
            config: None,
            channel: 0,
            busy: false,
            standby: false,
            begun: None,
        }
    }
}

impl<SPI, IRQ, D> Rfm22b<SPI, IRQ, NoPin, D> {
    /// A driver for a board that ties SDN low (software reset only).
    pub fn new_without_sdn(spi: SPI, irq: IRQ, delay: D) -> Self {
        Self::from_parts(spi, irq, NoPin, false, delay)
    }
}

impl<SPI, IRQ, SDN, D> Rfm22b<SPI, IRQ, SDN, D> {
    /// Gives the parts back.
    pub fn release(self) -> (SPI, IRQ, SDN, D) {
        (self.bus.release(), self.irq, self.sdn, self.delay)
    }

    /// Whether SDN is a pin the MCU drives (built with [`Rfm22b::new`]).
    pub fn sdn_present(&self) -> bool {
        self.sdn_present
    }

    /// The configuration programmed by [`Rfm22b::init`].
    pub fn config(&self) -> Option<&Config> {
        self.config.as_ref()
    }

    /// The current hop channel.
    pub fn channel(&self) -> u8 {
        self.channel
    }
}

impl<SPI, IRQ, SDN, D> Rfm22b<SPI, IRQ, SDN, D>
where
    SPI: SpiDevice,
    IRQ: Wait,
    SDN: OutputPin,
    D: DelayNs,
{
    /// Resets the chip (SDN pulse if wired, then software reset), checks it, and programs
    /// `config`. Returns the silicon revision.
    ///
    /// Cancel-safety: dropping it leaves the chip half-configured; call `init` again.
    pub async fn init(&mut self, config: Config) -> Result<ChipInfo, Error<SPI::Error>> {
        config.validate()?;
        self.config = Some(config);
        self.channel = 0;
        self.reinit().await
    }

    /// Resets and re-programs the stored configuration (after a chip reset or brown-out).
    ///
    /// Cancel-safety: as [`Rfm22b::init`].
    pub async fn reinit(&mut self) -> Result<ChipInfo, Error<SPI::Error>> {
        let config = self.config.ok_or(Error::NotInitialised)?;
        let info = self.reset().await?;
        self.configure(&config).await?;
        Ok(info)
    }

    /// Hard reset through SDN (if wired), probe, software reset with chip-ready wait,
    /// probe again; leaves the chip in READY with all interrupts off. An absent chip (bus
    /// reads all 0x00 or all 0xFF) gives [`Error::NotAnSi4432`], never a hang.
    ///
    /// Cancel-safety: safe to drop; the next `reset` starts over.
    pub async fn reset(&mut self) -> Result<ChipInfo, Error<SPI::Error>> {
        self.busy = false;
        self.standby = false;
        if self.sdn_present {
            self.sdn.set_high().map_err(|_| Error::Pin)?;
            self.delay.delay_ms(SDN_HIGH_MS).await;
            self.sdn.set_low().map_err(|_| Error::Pin)?;
            self.delay.delay_ms(SDN_LOW_MS).await;
        }
        self.probe().await?;
        self.software_reset().await?;
        self.bus
            .write_burst(INTERRUPT_ENABLE_1, &[0x00, 0x00])
            .await?;
        self.read_status().await?;
        self.probe().await
    }

    /// Reads the identification registers (0x00/0x01).
    ///
    /// Cancel-safety: safe (a register read).
    pub async fn probe(&mut self) -> Result<ChipInfo, Error<SPI::Error>> {
        let mut id = [0u8; 2];
        self.bus.read_burst(DEVICE_TYPE, &mut id).await?;
        crate::probe::check_identity(id)
    }

    /// Software reset (0x07 = 0x80), then polls for chip-ready up to 50 ms.
    async fn software_reset(&mut self) -> Result<(), Error<SPI::Error>> {
        self.bus.write(OPERATING_MODE_1, MODE_SWRESET).await?;
        for _ in 0..CHIP_READY_POLLS {
            self.delay.delay_ms(1).await;
            if self.read_status().await?.chip_ready() {
                return Ok(());
            }
        }
        Err(Error::Timeout)
    }

    /// Reads (and so clears) both interrupt status registers, releasing nIRQ.
    pub(crate) async fn read_status(&mut self) -> Result<Status, Error<SPI::Error>> {
        crate::irq::read_status(&mut self.bus).await
    }

    /// Writes every register of `config`, in bursts (about 20 SPI transactions).
    pub(crate) async fn configure(&mut self, config: &Config) -> Result<(), Error<SPI::Error>> {
        let [g0, g1, g2] = config.gpio.registers();
        let modem = config.modem.registers();
        let [dr1, dr0, m70, m71, fd] = modem.block_6e;
        let m70 = m70 | u8::from(config.packet.whitening());
        let packet = &config.packet;
        let [band, fc1, fc0] = config.carrier.registers();
        // One table, written by one loop: each awaited write is a state of the future, and
        // a state is flash (issue 33).
        let blocks: [(u8, &[u8]); 19] = [
            (OPERATING_MODE_1, &[MODE_XTON]),
            (OPERATING_MODE_2, &[0x00]),
            (CRYSTAL_LOAD, &[config.crystal_load.register()]),
            (GPIO0_CONFIG, &[g0, g1, g2, 0x00]),
            // Temperature sensor on the ADC, −64…+64 °C range, 0.5 °C steps (0x12 = 0x20).
            (ADC_CONFIG, &[0x00, 0x00]),
            (TEMPERATURE_CONTROL, &[0x20, 0x00]),
            (
                RSSI_THRESHOLD,
                &[measure::rssi_raw(config.clear_channel_threshold_dbm)],
            ),
            (IF_FILTER_BANDWIDTH, &modem.block_1c),
            (AFC_LIMITER, &[modem.afc_limiter]),
            (CHARGE_PUMP_TRIM, &[modem.charge_pump]),
            (AGC_OVERRIDE, &[modem.agc]),
            (TX_DATA_RATE_1, &[dr1, dr0, m70, m71, fd]),
            (DATA_ACCESS_CONTROL, &[packet.data_access_control()]),
            (HEADER_CONTROL_1, &packet.header_block()),
            (SYNC_WORD_3, &packet.address_block()),
            (TX_POWER, &[config.tx_power.register(config.lna_switch)]),
            (FREQUENCY_OFFSET_1, &[0x00, 0x00, band, fc1, fc0]),
            (
                HOP_CHANNEL,
                &[self.channel, config.channel_spacing.register()],
            ),
            (TX_FIFO_ALMOST_FULL, &config.fifo.registers()),
        ];
        for (address, data) in blocks {
            self.bus.write_burst(address, data).await?;
        }
        Ok(())
    }

    pub(crate) async fn clear_status(&mut self) -> Result<(), Error<SPI::Error>> {
        let status = self.read_status().await?;
        // All ones is a bus with no chip on it, not a reset: the operation's own presence
        // check reports that (as NotAnSi4432) without a pointless re-init first.
        let floating = status.status1 == 0xFF && status.status2 == 0xFF;
        if status.power_on_reset() && !floating && self.config.is_some() {
            return Err(self.recover().await);
        }
        Ok(())
    }

    /// After a status read showed a power-on reset: re-initialise, report the reset.
    pub(crate) async fn recover(&mut self) -> Error<SPI::Error> {
        match self.reinit().await {
            Ok(_) => Error::ChipReset,
            Err(e) => e,
        }
    }

    /// Clears the selected FIFOs (0x08 bit 1 RX, bit 0 TX: write 1, then 0).
    pub(crate) async fn clear_fifos(&mut self, bits: u8) -> Result<(), Error<SPI::Error>> {
        self.bus.write(OPERATING_MODE_2, bits).await?;
        self.bus.write(OPERATING_MODE_2, 0x00).await
    }

    /// Ends a TX/RX: on success only disables interrupts; on failure also goes to READY and
    /// flushes `fifos`; a POR triggers re-init; a timeout checks the chip is still there.
    /// Not generic over a value: one copy of it serves TX and RX (issue 33).
    pub(crate) async fn finish(
        &mut self,
        outcome: Result<(), Error<SPI::Error>>,
        fifos: u8,
    ) -> Result<(), Error<SPI::Error>> {
        match outcome {
            Ok(()) => {
                self.bus
                    .write_burst(INTERRUPT_ENABLE_1, &[0x00, 0x00])
                    .await?;
                self.busy = false;
                Ok(())
            }
            Err(Error::ChipReset) => Err(self.recover().await),
            Err(e) => {
                self.idle().await?;
                self.clear_fifos(fifos).await?;
                if matches!(e, Error::Timeout) {
                    self.probe().await?;
                }
                Err(e)
            }
        }
    }

    /// If a previous TX/RX was dropped mid-way, stop it before starting anew.
    pub(crate) async fn abort_if_busy(&mut self) -> Result<(), Error<SPI::Error>> {
        if self.busy {
            self.idle().await?;
        }
        Ok(())
    }
}
