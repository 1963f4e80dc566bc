//! A packet-level radio on the [`Medium`]: SPI set-up, PLL settling and airtime are charged in virtual
//! time exactly as the slot budget assumes (`link::rate`), so link timing is exercised too.

use std::convert::Infallible;
use std::future::poll_fn;
use std::task::Poll;

use super::medium::Medium;
use crate::link::rate::PLL_SETTLE_US;
use crate::link::{LinkRx, PacketRadio, RadioConfig, RateMode};
use sim_exec::VirtualTime;

/// One mock radio (node) on a medium.
pub struct MockRadio {
    medium: Medium,
    time: VirtualTime,
    node: usize,
    config: RadioConfig,
    frequency_hz: u32,
    transmitted: u64,
    /// A packet begun ([`PacketRadio::begin_transmit`]): when its first bit goes out.
    begun_start_us: Option<u64>,
}

impl MockRadio {
    /// The radio of `node` (from [`Medium::add_node`]).
    pub fn new(medium: Medium, node: usize) -> Self {
        let time = medium.time();
        Self {
            medium,
            time,
            node,
            config: RadioConfig {
                rate: RateMode::L50,
                header: [0; 4],
                base_hz: 0,
                spacing_hz: 0,
                reduced_power: false,
            },
            frequency_hz: 0,
            transmitted: 0,
            begun_start_us: None,
        }
    }

    /// Its node index.
    pub fn node(&self) -> usize {
        self.node
    }

    /// Current frequency.
    pub fn frequency_hz(&self) -> u32 {
        self.frequency_hz
    }

    /// Packets sent.
    pub fn transmitted(&self) -> u64 {
        self.transmitted
    }
}

impl PacketRadio for MockRadio {
    type Error = Infallible;

    async fn configure(&mut self, config: &RadioConfig) -> Result<(), Infallible> {
        self.config = *config;
        self.medium.configure(self.node, config.rate, config.header);
        Ok(())
    }

    async fn set_channel(&mut self, channel: u8) -> Result<(), Infallible> {
        self.frequency_hz = self.config.channel_hz(channel);
        Ok(())
    }

    async fn transmit(&mut self, frame: &[u8]) -> Result<(), Infallible> {
        self.begin_transmit(frame.len()).await?;
        self.finish_transmit(frame).await
    }

    async fn begin_transmit(&mut self, _len: usize) -> Result<(), Infallible> {
        let rate = self.config.rate;
        self.begun_start_us =
            Some(self.time.now_us() + u64::from(rate.tx_setup_us() + PLL_SETTLE_US));
        Ok(())
    }

    async fn finish_transmit(&mut self, frame: &[u8]) -> Result<(), Infallible> {
        let rate = self.config.rate;
        // The packet went on the air when begun (its bytes are in the FIFO in time).
        let start = self
            .begun_start_us
            .take()
            .unwrap_or_else(|| self.time.now_us());
        let end = start + u64::from(rate.airtime_us(frame.len()));
        self.medium
            .transmit(self.node, start, end, self.frequency_hz, frame);
        self.transmitted += 1;
        self.time.sleep_until(end).await;
        Ok(())
    }

    async fn receive(&mut self, buf: &mut [u8], timeout_us: u32) -> Result<LinkRx, Infallible> {
        let now = self.time.now_us();
        let ready = now + u64::from(PLL_SETTLE_US);
        let mut deadline = now + u64::from(timeout_us);
        self.medium.start_listening(self.node);
        let (medium, time, node, freq) = (&self.medium, &self.time, self.node, self.frequency_hz);
        let mut registered = false;
        let mut extended = false;
        let outcome = poll_fn(|_| {
            if let Some(d) = medium.poll_reception(node, freq, ready) {
                let len = d.bytes.len().min(buf.len());
                if let (Some(dst), Some(src)) = (buf.get_mut(..len), d.bytes.get(..len)) {
                    dst.copy_from_slice(src);
                }
                return Poll::Ready(LinkRx::Packet {
                    len,
                    rssi_dbm: d.rssi_dbm,
                });
            }
            if time.now_us() >= deadline {
                // Like the driver: a packet whose sync word came in time is completed.
                match medium.arriving_end_us(node, freq, ready) {
                    Some(end) if !extended => {
                        extended = true;
                        deadline = end;
                        time.wake_all_at(end);
                        return Poll::Pending;
                    }
                    _ => return Poll::Ready(LinkRx::Timeout),
                }
            }
            if !registered {
                time.wake_all_at(deadline);
                registered = true;
            }
            Poll::Pending
        })
        .await;
        Ok(outcome)
    }
}
