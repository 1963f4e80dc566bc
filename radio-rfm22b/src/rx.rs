//! Reception: arm RX, latch RSSI and AFC at sync detect, drain the FIFO on almost-full for
//! packets over 64 bytes, finish on valid-packet or CRC error (datasheet "Packet Handler"; the Tau Labs
//! interrupt set 0x05 = 0x93 with sync detect from 0x06).

use core::pin::pin;

use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;

use crate::irq::{Wake, read_status, wait_for_irq};
use crate::measure;
use crate::packet::PacketLength;
use crate::registers::*;
use crate::{Error, Rfm22b};

/// Signal measurements latched when the sync word was detected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RxSignal {
    /// RSSI at sync detect in dBm (read at packet end if the sync interrupt was missed).
    pub rssi_dbm: i16,
    /// The raw RSSI byte behind `rssi_dbm` (OpenLRSng reports this).
    pub rssi_raw: u8,
    /// The AFC correction at sync detect, Hz (signed; how far the sender was off).
    pub afc_offset_hz: i32,
}

/// A valid packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RxPacket {
    /// Payload bytes written to the start of the buffer.
    pub len: usize,
    /// The received header (0x47–0x4A), first on air first; bytes beyond the configured
    /// header length are not part of this packet.
    pub header: [u8; 4],
    /// Signal quality.
    pub signal: RxSignal,
}

/// What a [`Rfm22b::receive`] ended with. Rejected packets are outcomes, not errors.
///
/// The chip's view of a reception; the TauLink link sees a narrower one
/// (`telemetry::link::LinkRx`, mapped in the `telemetry` feature's adapter): two layers,
/// so the driver needs no protocol crate and the link no particular chip (README, "Two
/// layers").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RxOutcome {
    /// A packet passed the header check and the CRC.
    Packet(RxPacket),
    /// A packet arrived with a CRC error; it was discarded.
    CrcError(RxSignal),
    /// A packet longer than the buffer arrived; it was discarded.
    TooLong {
        /// Its length.
        len: usize,
        /// Signal quality.
        signal: RxSignal,
    },
    /// Nothing arrived before the timeout.
    Timeout,
}

impl<SPI, IRQ, SDN, D> Rfm22b<SPI, IRQ, SDN, D>
where
    SPI: SpiDevice,
    IRQ: Wait,
    SDN: OutputPin,
    D: DelayNs,
{
    /// Listens on the current channel for up to `timeout_us` for a packet to start, and
    /// receives it into `buf` (up to 255 bytes; longer than 64 streams through the FIFO). A
    /// packet whose sync word arrived before the timeout is completed (for at most the
    /// airtime of a 255-byte packet more). The chip ends in READY whatever the outcome.
    ///
    /// Errors: [`Error::ChipReset`] (a power-on reset was seen; the chip has been
    /// re-initialised), [`Error::FifoError`] (the FIFO overflowed; flushed), bus errors.
    ///
    /// Cancel-safety: dropping the future loses any packet in flight and leaves the chip in
    /// RX; the next operation on the driver stops it first.
    pub async fn receive(
        &mut self,
        buf: &mut [u8],
        timeout_us: u32,
    ) -> Result<RxOutcome, Error<SPI::Error>> {
        let config = self.config.ok_or(Error::NotInitialised)?;
        self.abort_if_busy().await?;
        self.clear_fifos(FFCLR_RX).await?;
        self.bus
            .write_burst(
                INTERRUPT_ENABLE_1,
                &[
                    IRQ1_FIFO_ERROR | IRQ1_RX_ALMOST_FULL | IRQ1_PACKET_VALID | IRQ1_CRC_ERROR,
                    IRQ2_SYNC_DETECTED,
                ],
            )
            .await?;
        self.clear_status().await?;
        self.busy = true;
        self.bus
            .write(OPERATING_MODE_1, MODE_RXON | MODE_XTON)
            .await?;

        // The timeout bounds the wait for a packet to *start*: once its sync word was seen,
        // the packet gets as long as the longest packet takes on air to complete.
        let completion_us = config
            .packet
            .airtime_us(&config.modem, u8::MAX)
            .saturating_add(COMPLETION_MARGIN_US);
        let waking = core::mem::take(&mut self.standby);
        let outcome = {
            let Self {
                irq, delay, bus, ..
            } = &mut *self;
            let mut rx = Reception {
                buf,
                got: 0,
                signal: None,
                high_band: config.carrier.high_band(),
                rssi_offset: config.packet.rssi_offset(),
                drain_len: config.fifo.rx_drain_len(),
                fixed_len: match config.packet.length() {
                    PacketLength::Fixed(n) => Some(usize::from(n)),
                    PacketLength::Variable => None,
                },
                waking,
            };
            let mut budget_us = timeout_us;
            let mut extended = false;
            'phase: loop {
                let mut deadline = pin!(delay.delay_us(budget_us));
                let mut expired = false;
                loop {
                    match wait_for_irq(irq, deadline.as_mut(), &mut expired).await {
                        Ok(Wake::Irq) => {}
                        Ok(Wake::Deadline) if rx.signal.is_some() && !extended => {
                            // Only a packet really being received (0x31 pkrx) earns the extra
                            // time: a sync word whose header the chip then refused (another
                            // link on the channel) must not stretch every receive.
                            if bus.read(EZMAC_STATUS).await? & EZMAC_PKRX == 0 {
                                break 'phase Err(Error::Timeout);
                            }
                            extended = true;
                            budget_us = completion_us;
                            continue 'phase;
                        }
                        Ok(Wake::Deadline) => break 'phase Err(Error::Timeout),
                        Err(_) => break 'phase Err(Error::Pin),
                    }
                    if let Some(done) = rx.service(bus).await? {
                        break 'phase done;
                    }
                }
            }
        };
        let (received, ended) = match outcome {
            Ok(RxOutcome::Packet(p)) => {
                // The chip leaves RX by itself after a valid packet; make READY explicit so
                // no second packet starts filling the FIFO.
                self.bus.write(OPERATING_MODE_1, MODE_XTON).await?;
                (RxOutcome::Packet(p), Ok(()))
            }
            // Discarded packets: back to READY with an empty FIFO, as after a timeout.
            Ok(other) => {
                self.idle().await?;
                self.clear_fifos(FFCLR_RX).await?;
                return Ok(other);
            }
            Err(e) => (RxOutcome::Timeout, Err(e)),
        };
        // One clean-up for every ending; a timeout that clean-up confirms is no error.
        let timed_out = matches!(ended, Err(Error::Timeout));
        match self.finish(ended, FFCLR_RX).await {
            Ok(()) => Ok(received),
            Err(Error::Timeout) if timed_out => Ok(RxOutcome::Timeout),
            Err(e) => Err(e),
        }
    }
}

/// Slack on top of the longest packet's airtime once a sync word was seen.
const COMPLETION_MARGIN_US: u32 = 2_000;

/// The state of one reception between interrupts.
struct Reception<'a> {
    buf: &'a mut [u8],
    got: usize,
    signal: Option<RxSignal>,
    high_band: bool,
    rssi_offset: u8,
    drain_len: usize,
    fixed_len: Option<usize>,
    /// The chip left standby for this reception, so a chip-ready flag is expected.
    waking: bool,
}

impl Reception<'_> {
    /// Handles one nIRQ: reads the status, latches RSSI/AFC at sync, drains the FIFO.
    /// `Some` ends the reception.
    async fn service<SPI: SpiDevice>(
        &mut self,
        bus: &mut crate::Bus<SPI>,
    ) -> Result<Option<Result<RxOutcome, Error<SPI::Error>>>, Error<SPI::Error>> {
        let status = read_status(bus).await?;
        if status.reset_seen(self.waking) {
            return Ok(Some(Err(Error::ChipReset)));
        }
        if status.fifo_error() {
            return Ok(Some(Err(Error::FifoError)));
        }
        if status.sync_detected() {
            // Latched afresh at every sync: a packet the header check dropped silently
            // must not lend its RSSI to the next one.
            self.signal = Some(latch_signal(bus, self.high_band, self.rssi_offset).await?);
        }
        if status.crc_error() {
            let signal = self.signal(bus).await?;
            return Ok(Some(Ok(RxOutcome::CrcError(signal))));
        }
        if !(status.packet_valid() || status.rx_almost_full()) {
            return Ok(None);
        }
        // Received header 0x47–0x4A and length 0x4B in one burst.
        let mut head = [0u8; 5];
        bus.read_burst(RECEIVED_HEADER_3, &mut head).await?;
        let [h3, h2, h1, h0, rx_len] = head;
        let len = self.fixed_len.unwrap_or(usize::from(rx_len));
        if len > self.buf.len() {
            let signal = self.signal(bus).await?;
            return Ok(Some(Ok(RxOutcome::TooLong { len, signal })));
        }
        let remaining = len.saturating_sub(self.got);
        let take = if status.packet_valid() {
            remaining
        } else {
            self.drain_len.min(remaining)
        };
        if let Some(dst) = self.buf.get_mut(self.got..self.got + take) {
            bus.read_burst(FIFO, dst).await?;
            self.got += take;
        }
        if !status.packet_valid() {
            return Ok(None);
        }
        let signal = self.signal(bus).await?;
        Ok(Some(Ok(RxOutcome::Packet(RxPacket {
            len: self.got,
            header: [h3, h2, h1, h0],
            signal,
        }))))
    }

    /// The signal latched at sync, or read now if the sync interrupt was not seen.
    async fn signal<SPI: SpiDevice>(
        &mut self,
        bus: &mut crate::Bus<SPI>,
    ) -> Result<RxSignal, Error<SPI::Error>> {
        match self.signal {
            Some(signal) => Ok(signal),
            None => latch_signal(bus, self.high_band, self.rssi_offset).await,
        }
    }
}

/// Reads RSSI (0x26) and the AFC correction (0x2B, 0x2C) at sync detect.
async fn latch_signal<SPI: SpiDevice>(
    bus: &mut crate::Bus<SPI>,
    high_band: bool,
    rssi_offset: u8,
) -> Result<RxSignal, Error<SPI::Error>> {
    let rssi_raw = bus.read(RSSI).await?;
    let mut afc = [0u8; 2];
    bus.read_burst(AFC_CORRECTION, &mut afc).await?;
    let [afc_high, afc_low] = afc;
    Ok(RxSignal {
        rssi_dbm: measure::rssi_dbm(rssi_raw, rssi_offset),
        rssi_raw,
        afc_offset_hz: measure::afc_offset_hz(afc_high, afc_low, high_band),
    })
}
