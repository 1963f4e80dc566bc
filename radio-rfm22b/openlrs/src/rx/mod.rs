//! The receiver role as a sans-IO state machine: bind listening, following the hop sequence,
//! the fast re-hop after a missed packet, slow hopping after `hopcount` misses, failsafe, and
//! the telemetry reply with its sequence handshake (OpenLRSng
//! `RX.h`). Time is `now_us` from the caller; nothing here touches a radio.

use heapless::Vec;

use super::bind::{self, BindData, BindReception};
use super::downlink::DownlinkSender;
use super::hopping;
use super::telemetry::{self, LinkInfo, LinkQuality, RssiSampler};
use super::timing;
use super::uplink::{self, Uplink};

mod events;
#[cfg(test)]
mod tests;

pub use events::{Command, Config, Output, Reception, Tick};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Bind { until_us: Option<u64> },
    Link,
}

/// The receiver.
#[derive(Debug, Clone)]
pub struct Receiver {
    config: Config,
    mode: Mode,
    data: Option<BindData>,
    interval_us: u32,
    hop_count: u8,
    hop_index: u8,
    link_acquired: bool,
    last_packet_us: u64,
    lost_packets: u8,
    link_lost_at_us: Option<u64>,
    failsafe_active: bool,
    failsafe_saved: bool,
    quality: LinkQuality,
    downlink: DownlinkSender,
    link_info: LinkInfo,
    rssi: RssiSampler,
}

impl Receiver {
    /// A receiver with optionally stored bind data (invalid or other-version data is ignored).
    pub fn new(config: Config, stored: Option<BindData>) -> Self {
        let data = stored
            .filter(|d| d.version == config.version.byte() && d.validate_for(config.band).is_ok());
        Self {
            config,
            mode: Mode::Bind { until_us: None },
            data,
            interval_us: 0,
            hop_count: 0,
            hop_index: 0,
            link_acquired: false,
            last_packet_us: 0,
            lost_packets: 0,
            link_lost_at_us: None,
            failsafe_active: false,
            failsafe_saved: false,
            quality: LinkQuality(0),
            downlink: DownlinkSender::new(),
            rssi: RssiSampler::default(),
            link_info: LinkInfo {
                rssi: 0,
                analog0: 0,
                analog1: 0,
                afc: 0,
                link_quality: 0,
            },
        }
    }

    /// Boot: listen for bind packets (briefly if already bound), or go straight to the link.
    pub fn start(&mut self, now_us: u64) -> Command {
        match (self.data, self.config.bind_window_us) {
            (Some(data), None) => self.start_link(now_us, data),
            (Some(_), Some(window)) => {
                self.mode = Mode::Bind {
                    until_us: Some(now_us + u64::from(window)),
                };
                Command::ListenBind
            }
            (None, _) => {
                self.mode = Mode::Bind { until_us: None };
                Command::ListenBind
            }
        }
    }

    fn start_link(&mut self, now_us: u64, data: BindData) -> Command {
        self.data = Some(data);
        self.mode = Mode::Link;
        // Only validated bind data gets here (`new` filters, bind packets are checked), so
        // the profile exists; the fallback merely keeps the arithmetic finite.
        self.interval_us = timing::interval_us(&data).unwrap_or(u32::MAX / 64);
        self.hop_count = data.hop_count() as u8;
        self.hop_index = 0;
        self.link_acquired = false;
        self.last_packet_us = now_us;
        self.lost_packets = 0;
        Command::StartLink(data)
    }

    /// The bind data in use, if bound.
    pub fn bind_data(&self) -> Option<&BindData> {
        self.data.as_ref()
    }

    /// Whether the receiver is on the link (as opposed to listening for bind packets).
    pub fn is_linked(&self) -> bool {
        self.mode == Mode::Link
    }

    /// Current hop index.
    pub fn hop_index(&self) -> u8 {
        self.hop_index
    }

    /// Whether failsafe values are in force.
    pub fn failsafe_active(&self) -> bool {
        self.failsafe_active
    }

    /// Uplink link quality 0..15 over the last 15 slots.
    pub fn link_quality(&self) -> u8 {
        self.quality.rx_quality()
    }

    /// The 10-bit AFC correction (0x2B/0x2C) read after the last packet, for the next
    /// link-info frame.
    pub fn set_afc(&mut self, afc: u16) {
        self.link_info.afc = afc;
    }

    /// An RSSI reading requested by [`Tick::sample_rssi`].
    pub fn on_rssi_sample(&mut self, rssi: u8) {
        self.rssi.record(rssi);
        self.link_info.rssi = rssi;
    }

    /// RSSI averaged over 9 slots and smoothed, as OpenLRSng's `smoothRSSI`.
    pub fn smoothed_rssi(&self) -> u8 {
        self.rssi.smoothed()
    }

    /// The RX's two analog inputs (ADC >> 2) for the next link-info frame.
    pub fn set_analog_inputs(&mut self, analog0: u8, analog1: u8) {
        self.link_info.analog0 = analog0;
        self.link_info.analog1 = analog1;
    }

    /// Queues RX UART bytes for the downlink; returns how many did not fit.
    pub fn queue_serial(&mut self, data: &[u8]) -> usize {
        self.downlink.queue_serial(data)
    }

    /// Bytes [`Receiver::queue_serial`] still takes whole.
    pub fn serial_free(&self) -> usize {
        self.downlink.serial_free()
    }

    /// When [`Receiver::poll`] next has something to do.
    pub fn next_deadline_us(&self) -> Option<u64> {
        match self.mode {
            Mode::Bind { until_us } => until_us,
            Mode::Link => {
                let interval = u64::from(self.interval_us);
                let hop_deadline = if !self.link_acquired || self.lost_packets >= self.hop_count {
                    self.last_packet_us + interval * u64::from(self.hop_count) + 1
                } else {
                    self.last_packet_us + u64::from(timing::rx_hop_timeout_us(self.interval_us)) + 1
                };
                let failsafe_deadline = self
                    .link_lost_at_us
                    .filter(|_| !self.failsafe_active && self.config.failsafe_delay != 0)
                    .map(|t| t + self.failsafe_delay_us() + 1);
                let rssi_deadline = self
                    .rssi
                    .due_us(self.last_packet_us, self.interval_us, self.lost_packets)
                    .filter(|_| self.link_acquired);
                Some(
                    [failsafe_deadline, rssi_deadline]
                        .into_iter()
                        .flatten()
                        .fold(hop_deadline, u64::min),
                )
            }
        }
    }

    fn failsafe_delay_us(&self) -> u64 {
        u64::from(timing::delay_in_ms(u16::from(self.config.failsafe_delay))) * 1000
    }

    fn hop(&mut self) -> Command {
        if let Some(data) = &self.data {
            self.hop_index = hopping::next_index(data, self.hop_index);
        }
        Command::Hop(self.hop_index)
    }

    /// Timer processing: missed packets, slow hopping, failsafe, the end of the bind window.
    pub fn poll(&mut self, now_us: u64) -> Tick {
        let mut tick = Tick::default();
        match self.mode {
            Mode::Bind { until_us: Some(t) } if now_us >= t => {
                if let Some(data) = self.data {
                    tick.command = Some(self.start_link(now_us, data));
                }
            }
            Mode::Bind { .. } => {}
            Mode::Link => {
                // Only once a packet has been heard: before that no packet is due to be on air
                // (OpenLRSng samples regardless; the value is not used until then either).
                tick.sample_rssi = self.link_acquired
                    && self.rssi.take_due(
                        now_us,
                        self.last_packet_us,
                        self.interval_us,
                        self.lost_packets,
                    );
                let interval = u64::from(self.interval_us);
                let since = now_us.saturating_sub(self.last_packet_us);
                let slow_dwell = interval * u64::from(self.hop_count);
                if !self.link_acquired {
                    if since > slow_dwell {
                        self.last_packet_us = now_us;
                        tick.command = Some(self.hop());
                    }
                } else if self.lost_packets < self.hop_count
                    && since > u64::from(timing::rx_hop_timeout_us(self.interval_us))
                {
                    // One slot missed: hop on the TX's schedule, keep the nominal grid.
                    self.quality.record(false);
                    if self.lost_packets == 0 {
                        self.link_lost_at_us = Some(now_us);
                    }
                    self.lost_packets += 1;
                    self.last_packet_us += interval;
                    tick.command = Some(self.hop());
                } else if self.lost_packets >= self.hop_count && since > slow_dwell {
                    // Lost: dwell a whole hop cycle per channel so the TX comes round to us.
                    self.quality = LinkQuality(0);
                    self.last_packet_us = now_us;
                    tick.command = Some(self.hop());
                }
                if let Some(lost_at) = self.link_lost_at_us
                    && !self.failsafe_active
                    && self.config.failsafe_delay != 0
                    && now_us.saturating_sub(lost_at) > self.failsafe_delay_us()
                {
                    self.failsafe_active = true;
                    tick.failsafe_started = true;
                }
            }
        }
        tick
    }

    /// Handles a packet that passed the radio's header and CRC checks.
    pub fn on_packet(&mut self, now_us: u64, packet: &[u8]) -> Reception {
        match self.mode {
            Mode::Bind { .. } => self.on_bind_packet(now_us, packet),
            Mode::Link => self.on_link_packet(now_us, packet),
        }
    }

    fn on_bind_packet(&mut self, now_us: u64, packet: &[u8]) -> Reception {
        match bind::receive_bind_packet(packet, self.config.version, self.config.band) {
            BindReception::Accepted(data) => Reception {
                reply: Vec::from_slice(&[bind::BIND_ACK]).ok(),
                command: Some(self.start_link(now_us, data)),
                output: Output::Bound(data),
            },
            BindReception::NotBind { .. } => Reception {
                reply: None,
                command: None,
                output: Output::Nothing,
            },
            refused => Reception {
                reply: None,
                command: None,
                output: Output::BindRefused(refused),
            },
        }
    }

    fn on_link_packet(&mut self, now_us: u64, packet: &[u8]) -> Reception {
        let Some(data) = self.data else {
            return Reception {
                reply: None,
                command: None,
                output: Output::Nothing,
            };
        };
        self.link_acquired = true;
        self.last_packet_us = now_us;
        self.lost_packets = 0;
        self.link_lost_at_us = None;
        self.failsafe_active = false;
        self.quality.record(true);
        let parsed = uplink::parse(data.channel_mode(), packet);
        let header = packet.first().copied().unwrap_or(0);
        let output = match parsed {
            Uplink::Servo {
                channels_bits,
                save_failsafe,
                ..
            } => {
                // Save once per press: only the first 0x01 packet after a 0x00 one counts.
                let first_of_press = save_failsafe && !self.failsafe_saved;
                self.failsafe_saved = save_failsafe;
                Output::Channels {
                    channels_bits,
                    save_failsafe: first_of_press,
                }
            }
            Uplink::Serial { data: bytes, .. } => {
                if self.downlink.accept_uplink_serial(header) {
                    Output::Serial(bytes)
                } else {
                    Output::Nothing
                }
            }
            other => Output::Unknown(other),
        };
        let reply = data
            .telemetry_enabled()
            .then(|| self.telemetry_reply(header));
        Reception {
            reply: reply.and_then(|f| Vec::from_slice(&f).ok()),
            command: Some(self.hop()),
            output,
        }
    }

    fn telemetry_reply(&mut self, uplink_header: u8) -> telemetry::Frame {
        let info = LinkInfo {
            link_quality: self.quality.rx_quality(),
            ..self.link_info
        };
        self.downlink.reply(uplink_header, &info)
    }
}
