//! Transmission: load the FIFO, start TX, refill on almost-empty for packets over 64 bytes,
//! finish on packet-sent (datasheet "Packet Handler"; Tau Labs' `PIOS_RFM22B_TransmitPacket` order).

use core::pin::pin;

use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;

use crate::fifo::FIFO_LEN;
use crate::irq::{Wake, read_status, wait_for_irq};
use crate::packet::PacketLength;
use crate::registers::*;
use crate::{Error, Rfm22b};

impl<SPI, IRQ, SDN, D> Rfm22b<SPI, IRQ, SDN, D>
where
    SPI: SpiDevice,
    IRQ: Wait,
    SDN: OutputPin,
    D: DelayNs,
{
    /// Sends `data` as one packet (1–255 bytes, or exactly the fixed length) on the current
    /// channel and waits up to `timeout_us` for it to leave. The chip returns to READY.
    ///
    /// Errors: [`Error::InvalidLength`], [`Error::Timeout`] (the chip is then put back in
    /// READY; if it no longer identifies, [`Error::NotAnSi4432`]), [`Error::ChipReset`] (a
    /// power-on reset was seen; the chip has been re-initialised), [`Error::FifoError`].
    ///
    /// Cancel-safety: dropping the future cuts the packet short and leaves the chip in TX;
    /// the next operation on the driver stops it first, so the driver stays consistent.
    pub async fn transmit(
        &mut self,
        data: &[u8],
        timeout_us: u32,
    ) -> Result<(), Error<SPI::Error>> {
        let len = data.len();
        self.check_length(len)?;
        self.begun = None;
        self.abort_if_busy().await?;
        // The SPI order of Tau Labs' `PIOS_RFM22B_TransmitPacket`: FIFO clear, length, FIFO,
        // interrupts, status clear, TX on.
        self.clear_and_set_length(len).await?;
        // Never `None` (`len` is `data.len()`); the checked split has no panic path.
        let (first, rest) = data.split_at_checked(FIFO_LEN).unwrap_or((data, &[]));
        self.bus.write_burst(FIFO, first).await?;
        self.enable_tx_interrupts(len).await?;
        self.tx_on().await?;
        let waking = core::mem::take(&mut self.standby);
        self.await_sent(rest, waking, timeout_us).await
    }

    /// Starts a packet of `len` bytes before its bytes are known (same lengths as
    /// [`Rfm22b::transmit`]): the FIFO is cleared, the length and interrupts set and the
    /// transmitter comes on, so the PLL settles and preamble and sync go out while the
    /// caller builds the bytes; [`Rfm22b::finish_transmit`] loads them. The chip takes each
    /// payload byte from the FIFO when it is due (datasheet §6.1, the TX FIFO streams during
    /// transmission, as the almost-empty refill of long packets relies on), so the first
    /// must be in by the end of the sync word, header and length: at 256 kbps with a 5-byte
    /// preamble and no header, 200 µs of PLL settle + 250 µs. A late byte underflows the
    /// FIFO: [`Error::FifoError`] and a frame that fails the receiver's CRC.
    ///
    /// The frame-independent SPI work happens here, before the caller latches its input;
    /// only the FIFO load follows it.
    pub async fn begin_transmit(&mut self, len: usize) -> Result<(), Error<SPI::Error>> {
        self.check_length(len)?;
        self.begun = None;
        self.abort_if_busy().await?;
        self.clear_and_set_length(len).await?;
        self.enable_tx_interrupts(len).await?;
        self.tx_on().await?;
        self.begun = Some((len, core::mem::take(&mut self.standby)));
        Ok(())
    }

    /// Loads the bytes of the packet [`Rfm22b::begin_transmit`] started (exactly its `len`)
    /// and waits up to `timeout_us` for it to leave, as [`Rfm22b::transmit`].
    ///
    /// Errors: [`Error::InvalidLength`] if nothing was begun or `data` is not its length
    /// (the chip is stopped), and those of [`Rfm22b::transmit`].
    pub async fn finish_transmit(
        &mut self,
        data: &[u8],
        timeout_us: u32,
    ) -> Result<(), Error<SPI::Error>> {
        let Some((len, waking)) = self.begun.take() else {
            return Err(Error::InvalidLength { len: data.len() });
        };
        if data.len() != len {
            self.abort_if_busy().await?;
            return Err(Error::InvalidLength { len: data.len() });
        }
        // Never `None` (`len` is `data.len()`); the checked split has no panic path.
        let (first, rest) = data.split_at_checked(FIFO_LEN).unwrap_or((data, &[]));
        self.bus.write_burst(FIFO, first).await?;
        self.await_sent(rest, waking, timeout_us).await
    }

    fn check_length(&self, len: usize) -> Result<(), Error<SPI::Error>> {
        let config = self.config.ok_or(Error::NotInitialised)?;
        let length_ok = match config.packet.length() {
            PacketLength::Variable => (1..=255).contains(&len),
            PacketLength::Fixed(n) => len == usize::from(n),
        };
        if length_ok {
            Ok(())
        } else {
            Err(Error::InvalidLength { len })
        }
    }

    /// TX FIFO clear and packet length.
    async fn clear_and_set_length(&mut self, len: usize) -> Result<(), Error<SPI::Error>> {
        let config = self.config.ok_or(Error::NotInitialised)?;
        self.clear_fifos(FFCLR_TX).await?;
        if let PacketLength::Variable = config.packet.length() {
            // `len` ≤ 255 was checked (`check_length`).
            self.bus.write(TRANSMIT_PACKET_LENGTH, len as u8).await?;
        }
        Ok(())
    }

    /// Interrupts (a refill for packets over the FIFO) and a status clear.
    async fn enable_tx_interrupts(&mut self, len: usize) -> Result<(), Error<SPI::Error>> {
        let refill = if len > FIFO_LEN {
            IRQ1_TX_ALMOST_EMPTY
        } else {
            0
        };
        self.bus
            .write_burst(
                INTERRUPT_ENABLE_1,
                &[IRQ1_FIFO_ERROR | IRQ1_PACKET_SENT | refill, 0x00],
            )
            .await?;
        self.clear_status().await?;
        Ok(())
    }

    async fn tx_on(&mut self) -> Result<(), Error<SPI::Error>> {
        self.busy = true;
        self.bus
            .write(OPERATING_MODE_1, MODE_TXON | MODE_XTON)
            .await?;
        Ok(())
    }

    /// Refills from `rest` on almost-empty until packet-sent, an error or `timeout_us`; the
    /// chip returns to READY.
    async fn await_sent(
        &mut self,
        mut rest: &[u8],
        waking: bool,
        timeout_us: u32,
    ) -> Result<(), Error<SPI::Error>> {
        let config = self.config.ok_or(Error::NotInitialised)?;
        let refill_len = config.fifo.tx_refill_len();
        let outcome = {
            let Self {
                irq, delay, bus, ..
            } = &mut *self;
            let mut deadline = pin!(delay.delay_us(timeout_us));
            let mut expired = false;
            let mut outcome = Err(Error::Timeout);
            loop {
                match wait_for_irq(irq, deadline.as_mut(), &mut expired).await {
                    Ok(Wake::Irq) => {}
                    Ok(Wake::Deadline) => break,
                    Err(_) => {
                        outcome = Err(Error::Pin);
                        break;
                    }
                }
                let status = read_status(bus).await?;
                if status.reset_seen(waking) {
                    outcome = Err(Error::ChipReset);
                    break;
                }
                if status.packet_sent() {
                    outcome = Ok(());
                    break;
                }
                if status.fifo_error() {
                    outcome = Err(Error::FifoError);
                    break;
                }
                if status.tx_almost_empty() && !rest.is_empty() {
                    let (chunk, tail) = rest.split_at(rest.len().min(refill_len));
                    bus.write_burst(FIFO, chunk).await?;
                    rest = tail;
                    if rest.is_empty() {
                        bus.write(INTERRUPT_ENABLE_1, IRQ1_FIFO_ERROR | IRQ1_PACKET_SENT)
                            .await?;
                    }
                }
            }
            outcome
        };
        self.finish(outcome, FFCLR_TX).await
    }
}
