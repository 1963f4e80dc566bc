//! The interrupt status pair (0x03/0x04; datasheet register table; read clears both and releases the
//! level-low nIRQ line) and the race of nIRQ against a deadline, every wait's timeout.

use core::future::{Future, poll_fn};
use core::pin::{Pin, pin};
use core::task::Poll;

use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;

use crate::registers::*;
use crate::{Bus, Error};

/// A snapshot of Interrupt/Status 1 and 2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// Register 0x03.
    pub status1: u8,
    /// Register 0x04.
    pub status2: u8,
}

impl Status {
    /// FIFO under/overflow.
    pub const fn fifo_error(self) -> bool {
        self.status1 & IRQ1_FIFO_ERROR != 0
    }
    /// TX FIFO fell to the almost-empty threshold.
    pub const fn tx_almost_empty(self) -> bool {
        self.status1 & IRQ1_TX_ALMOST_EMPTY != 0
    }
    /// RX FIFO reached the almost-full threshold.
    pub const fn rx_almost_full(self) -> bool {
        self.status1 & IRQ1_RX_ALMOST_FULL != 0
    }
    /// The packet has been sent.
    pub const fn packet_sent(self) -> bool {
        self.status1 & IRQ1_PACKET_SENT != 0
    }
    /// A valid packet was received.
    pub const fn packet_valid(self) -> bool {
        self.status1 & IRQ1_PACKET_VALID != 0
    }
    /// A packet with a CRC error was received.
    pub const fn crc_error(self) -> bool {
        self.status1 & IRQ1_CRC_ERROR != 0
    }
    /// The sync word was detected.
    pub const fn sync_detected(self) -> bool {
        self.status2 & IRQ2_SYNC_DETECTED != 0
    }
    /// The chip went through a power-on reset.
    pub const fn power_on_reset(self) -> bool {
        self.status2 & IRQ2_POWER_ON_RESET != 0
    }
    /// The crystal is running.
    pub const fn chip_ready(self) -> bool {
        self.status2 & IRQ2_CHIP_READY != 0
    }
    /// The chip has reset itself: the power-on-reset flag, or a chip-ready flag when the
    /// driver did not just wake the chip from standby (`waking`), where it is expected.
    pub const fn reset_seen(self, waking: bool) -> bool {
        self.power_on_reset() || (self.chip_ready() && !waking)
    }
}

/// What ended a [`wait_for_irq`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Wake {
    /// nIRQ is low (an enabled event is pending).
    Irq,
    /// The deadline passed first.
    Deadline,
}

/// Waits until nIRQ is low or `deadline` completes. The deadline always wins: `deadline_done`
/// records that the deadline future has completed (it must not be polled again), and once
/// it is set every call returns [`Wake::Deadline`] at once, whatever the pin. Only the call
/// in which the deadline completes still reports a low pin as [`Wake::Irq`], so an event
/// that became pending right at the deadline (a packet just received) is serviced once.
/// A line stuck low (an unpowered or browned-out module can read that way) therefore costs
/// status reads until the deadline, never a wait past it.
///
/// Cancel-safe: dropping it drops only the pin-wait future.
pub(crate) async fn wait_for_irq<IRQ: Wait, F: Future<Output = ()>>(
    irq: &mut IRQ,
    mut deadline: Pin<&mut F>,
    deadline_done: &mut bool,
) -> Result<Wake, IRQ::Error> {
    if *deadline_done {
        return Ok(Wake::Deadline);
    }
    let mut low = pin!(irq.wait_for_low());
    poll_fn(|cx| {
        let pin = low.as_mut().poll(cx);
        if !*deadline_done && deadline.as_mut().poll(cx).is_ready() {
            *deadline_done = true;
        }
        match pin {
            Poll::Ready(Ok(())) => Poll::Ready(Ok(Wake::Irq)),
            Poll::Ready(Err(e)) => Poll::Ready(Err(e)),
            Poll::Pending if *deadline_done => Poll::Ready(Ok(Wake::Deadline)),
            Poll::Pending => Poll::Pending,
        }
    })
    .await
}

/// Reads (and so clears) both interrupt status registers in one burst, releasing nIRQ.
pub(crate) async fn read_status<SPI: SpiDevice>(
    bus: &mut Bus<SPI>,
) -> Result<Status, Error<SPI::Error>> {
    let mut s = [0u8; 2];
    bus.read_burst(INTERRUPT_STATUS_1, &mut s).await?;
    let [status1, status2] = s;
    Ok(Status { status1, status2 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::convert::Infallible;

    /// An nIRQ input that always reads low.
    struct StuckLow;

    impl embedded_hal::digital::ErrorType for StuckLow {
        type Error = Infallible;
    }

    impl Wait for StuckLow {
        async fn wait_for_high(&mut self) -> Result<(), Infallible> {
            core::future::pending().await
        }
        async fn wait_for_low(&mut self) -> Result<(), Infallible> {
            Ok(())
        }
        async fn wait_for_rising_edge(&mut self) -> Result<(), Infallible> {
            core::future::pending().await
        }
        async fn wait_for_falling_edge(&mut self) -> Result<(), Infallible> {
            core::future::pending().await
        }
        async fn wait_for_any_edge(&mut self) -> Result<(), Infallible> {
            core::future::pending().await
        }
    }

    /// A deadline that completes on its `n`th poll.
    struct AfterPolls(u32);

    impl Future for AfterPolls {
        type Output = ();
        fn poll(mut self: Pin<&mut Self>, _: &mut core::task::Context<'_>) -> Poll<()> {
            self.0 = self.0.saturating_sub(1);
            if self.0 == 0 {
                Poll::Ready(())
            } else {
                Poll::Pending
            }
        }
    }

    #[test]
    fn a_stuck_low_line_cannot_outlast_the_deadline() {
        let mut irq = StuckLow;
        let mut deadline = pin!(AfterPolls(3));
        let mut done = false;
        let wakes: Vec<Wake> = (0..6)
            .map(|_| {
                embassy_futures::block_on(wait_for_irq(&mut irq, deadline.as_mut(), &mut done))
                    .unwrap()
            })
            .collect();
        // Two interrupts before the deadline, one serviced as it expires, then the deadline.
        assert_eq!(
            wakes,
            [
                Wake::Irq,
                Wake::Irq,
                Wake::Irq,
                Wake::Deadline,
                Wake::Deadline,
                Wake::Deadline
            ]
        );
    }
}
