//! The flight side of an OpenLRSng link (`link.protocol` = `openlrs38` / `openlrs39`): the link
//! task runs `openlrs`'s receiver role and hands the app what each `rx_step`
//! reported; the app turns it into the same thing the TauLink follower gives the loop
//! (channels on the CRSF scale, failsafe, failsafe counting, watchdog check-in,
//! `FlightApp::on_link_channels`), so the flight logic never knows which link runs.
//!
//! Telemetry goes back where OpenLRSng carries it: the RX's serial passthrough (8 bytes per
//! downlink frame), which carries the same COBS-framed message stream as TauLink's
//! downlink; the transmitter's serial uplink carries the module's messages (setting
//! changes). A message is queued only after two packets were answered with an empty serial
//! queue, so the transmitter keeps getting OpenLRSng's link-info frames (its RSSI and link
//! quality) between messages. OpenLRSng frames carry no authentication.
//!
//! Binding follows OpenLRSng's procedure but only on the owner's deliberate act, like
//! TauLink's: the console's `bind` opens a window ([`super::BIND_WINDOW_US`]) in which a
//! receiver without bind data listens on OpenLRSng's bind frequency; the bind data the
//! transmitter sent is stored (`link.olrs_*`) only inside that window and while disarmed.
//! Never bound over OpenLRSng (`link.olrs_magic` 0), the link task runs nothing.

use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;
use heapless::Deque;
use openlrs::channels::bits_to_ticks;
use openlrs::downlink::SERIAL_QUEUE_LEN;
use openlrs::quality::{quality_percent, rssi_dbm};
use openlrs::radio::{Clock, Error as RadioError, Radio};
use openlrs::roles::{RxEvent, rx_start, rx_step};
use openlrs::rx::{Config, Receiver};
use openlrs::{BindData, BindingVersion};
use telemetry::channels::MAX_CHANNELS;
use telemetry::messages::FRAMED_MAX_BYTES;

use super::FlightApp;
use super::link::{BindRequest, BindState, LinkStep};
use crate::pipeline::{openlrs_band, store_openlrs, stored_openlrs};
use crate::report::LinkSeen;

/// The receiver's failsafe delay in OpenLRSng's `delayInMs` code: 5 = 500 ms, the same as
/// the TauLink follower's [`super::FAILSAFE_US`] (OpenLRSng's own default is 1 s).
pub const OPENLRS_FAILSAFE_DELAY: u8 = 5;
/// Telemetry's `rate_mode` for an OpenLRSng link: this plus the modem profile (0..4), clear
/// of TauLink's rate codes.
pub const OPENLRS_RATE_CODE_BASE: u8 = 0x10;
/// Packets answered with an empty serial queue before the next message is queued.
const IDLE_REPLIES: u8 = 2;

/// What the app keeps of the OpenLRSng link between steps.
pub(super) struct OpenLrsSide {
    /// The newest channels, CRSF scale.
    channels: [u16; MAX_CHANNELS],
    /// Channels arrived since this link started.
    has_channels: bool,
    /// Framed message bytes waiting for room in the receiver's serial queue.
    pending: Deque<u8, FRAMED_MAX_BYTES>,
    /// Packets answered in a row while nothing waited to go down.
    idle_replies: u8,
    /// Channel packets received since boot.
    received: u32,
}

impl OpenLrsSide {
    pub(super) fn new() -> Self {
        Self {
            channels: [telemetry::channels::CHANNEL_CENTER; MAX_CHANNELS],
            has_channels: false,
            pending: Deque::new(),
            idle_replies: 0,
            received: 0,
        }
    }

    /// A new link run: nothing heard yet (the loop sees failsafe until channels come).
    fn restart(&mut self) {
        self.has_channels = false;
        self.pending.clear();
        self.idle_replies = 0;
    }
}

/// The receiver configuration the link task uses for `version` on `band`: OpenLRSng's, with
/// the TauLink failsafe delay and no bind window at start (binding is the console's).
fn config(version: BindingVersion, band: ::openlrs::RfmType) -> Config {
    Config {
        failsafe_delay: OPENLRS_FAILSAFE_DELAY,
        bind_window_us: None,
        ..Config::new(version, band)
    }
}

impl FlightApp {
    /// [`FlightApp::next_link_step`] when `link.protocol` is OpenLRSng.
    pub(super) fn next_openlrs_step(&mut self, version: BindingVersion) -> LinkStep {
        let config = config(version, openlrs_band(&self.live));
        if let Some(BindRequest { window_us, .. }) = self.take_bind_request() {
            return LinkStep::BindOpenLrs { config, window_us };
        }
        match stored_openlrs(&self.live, version) {
            Some(data) => {
                self.link.openlrs.restart();
                LinkStep::FollowOpenLrs { config, data }
            }
            None => LinkStep::WaitForBind,
        }
    }

    /// An OpenLRSng bind window ended: `bound` is what a transmitter sent, if one did.
    /// Stored (and a save requested) only inside a window the console opened and while
    /// disarmed; returns whether it was.
    pub fn on_openlrs_bind_result(&mut self, bound: Option<&BindData>) -> bool {
        let open = self.link.bind == BindState::Open;
        self.link.bind = BindState::Closed;
        let Some(data) = bound else {
            return false;
        };
        if !open || self.armed() {
            return false;
        }
        if store_openlrs(&mut self.live, data).is_ok() {
            self.request_save();
            return true;
        }
        false
    }

    /// After every OpenLRSng `rx_step` at `now_us`, with what it reported: channels and
    /// failsafe to the loop, the transmitter's serial bytes to the message reader, and
    /// telemetry into the receiver's serial queue.
    pub fn on_openlrs_step(&mut self, now_us: u64, rx: &mut Receiver, events: &[RxEvent]) {
        let mut answered = false;
        for event in events {
            match event {
                RxEvent::Channels { channels_bits, .. } => {
                    for (slot, bits) in self.link.openlrs.channels.iter_mut().zip(channels_bits) {
                        *slot = bits_to_ticks(*bits);
                    }
                    self.link.openlrs.has_channels = true;
                    self.link.openlrs.received = self.link.openlrs.received.saturating_add(1);
                    answered = true;
                }
                RxEvent::Serial(bytes) => {
                    self.on_uplink_bytes(bytes);
                    answered = true;
                }
                RxEvent::Bound(_) | RxEvent::FailsafeStarted => {}
            }
        }
        let failsafe = !self.link.openlrs.has_channels || rx.failsafe_active();
        let channels = self.link.openlrs.channels;
        self.on_link_channels(&channels, failsafe);
        self.feed_downlink(now_us, rx, answered);
    }

    fn feed_downlink(&mut self, now_us: u64, rx: &mut Receiver, answered: bool) {
        let Some(data) = rx.bind_data().copied() else {
            return;
        };
        if !data.telemetry_enabled() {
            return;
        }
        while rx.serial_free() > 0 {
            let Some(byte) = self.link.openlrs.pending.pop_front() else {
                break;
            };
            rx.queue_serial(&[byte]);
        }
        let quiet = self.link.openlrs.pending.is_empty() && rx.serial_free() == SERIAL_QUEUE_LEN;
        if !quiet {
            self.link.openlrs.idle_replies = 0;
            return;
        }
        if answered {
            self.link.openlrs.idle_replies = self.link.openlrs.idle_replies.saturating_add(1);
        }
        if self.link.openlrs.idle_replies < IDLE_REPLIES || !self.report_due(now_us) {
            return;
        }
        let seen = LinkSeen {
            rssi_dbm: i8::try_from(rssi_dbm(rx.smoothed_rssi())).unwrap_or(i8::MIN),
            lq_percent: quality_percent(rx.link_quality()),
            downlink: None,
            rate_mode: OPENLRS_RATE_CODE_BASE + data.modem_profile,
            received: self.link.openlrs.received,
            // The receiver role counts no misses; its link quality says how many.
            missed: 0,
            failsafes: self.link_failsafes(),
        };
        let mut buf = [0u8; FRAMED_MAX_BYTES];
        if let Some(framed) = self.next_report(seen, &mut buf) {
            for byte in framed {
                let _ = self.link.openlrs.pending.push_back(*byte);
            }
            self.link.openlrs.idle_replies = 0;
        }
    }
}

/// The link task's OpenLRSng receiver, shared by the firmware and the simulator so neither
/// re-implements it: the crate's step-wise role loop (`rx_start`, then `rx_step` forever),
/// with `on_step(now_us, rx, events)` after every step — the firmware passes
/// [`FlightApp::on_openlrs_step`] through its app lock. Returns only on a radio error.
/// A step waits at most one hop cycle (longer than the watchdog period at the slow
/// profiles), so the caller races this against its 50 ms check-in, as for TauLink.
pub use openlrs::roles::run_receiver_steps as run_openlrs_receiver;

/// The OpenLRSng bind window ([`LinkStep::BindOpenLrs`]): a receiver without bind data
/// listens on OpenLRSng's bind frequency until a transmitter's bind packet is accepted
/// (answered `'B'`, returned) or `window_us` passes (`None`).
pub async fn openlrs_bind_window<SPI, IRQ, D, C>(
    radio: &mut Radio<SPI, IRQ, D, C>,
    config: Config,
    window_us: u64,
) -> Result<Option<BindData>, RadioError<SPI::Error, IRQ::Error>>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    let mut rx = Receiver::new(config, None);
    let until = radio.now_us().saturating_add(window_us);
    rx_start(radio, &mut rx).await?;
    while radio.now_us() < until {
        let mut bound = None;
        rx_step(radio, &mut rx, &mut |event| {
            if let RxEvent::Bound(data) = event {
                bound = Some(data);
            }
        })
        .await?;
        if bound.is_some() {
            return Ok(bound);
        }
    }
    Ok(None)
}

#[cfg(test)]
#[path = "openlrs_tests.rs"]
mod tests;
