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
        let config = self.config.ok_or(Error::NotInitialised)?;
        let len = data.len();
        let length_ok = match config.packet.length() {
            PacketLength::Variable => (1..=255).contains(&len),
            PacketLength::Fixed(n) => len == usize::from(n),
        };
        if !length_ok {
            return Err(Error::InvalidLength { len });
        }
        self.abort_if_busy().await?;
        self.clear_fifos(FFCLR_TX).await?;
        if let PacketLength::Variable = config.packet.length() {
            // `len` ≤ 255 was checked above.
            self.bus.write(TRANSMIT_PACKET_LENGTH, len as u8).await?;
        }
        let (first, mut rest) = data.split_at(len.min(FIFO_LEN));
        self.bus.write_burst(FIFO, first).await?;
        let refill = if rest.is_empty() {
            0
        } else {
            IRQ1_TX_ALMOST_EMPTY
        };
        self.bus
            .write_burst(
                INTERRUPT_ENABLE_1,
                &[IRQ1_FIFO_ERROR | IRQ1_PACKET_SENT | refill, 0x00],
            )
            .await?;
        self.clear_status().await?;
        self.busy = true;
        self.bus
            .write(OPERATING_MODE_1, MODE_TXON | MODE_XTON)
            .await?;

        let refill_len = config.fifo.tx_refill_len();
        let waking = core::mem::take(&mut self.standby);
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
