//! The receiver role as a sans-IO state machine: bind listening, following the hop sequence,
//! the fast re-hop after a missed packet, slow hopping after `hopcount` misses, failsafe, and
//! the telemetry reply with its sequence handshake (RX.h; radio.md §1c "Hopping",
//! "Downlink", "Failsafe"). Time is `now_us` from the caller; nothing here touches a radio.

use heapless::Vec;

use super::bind::{self, BindData, BindReception};
use super::channels::MAX_CHANNELS;
use super::downlink::DownlinkSender;
use super::hopping;
use super::telemetry::{self, LinkInfo, LinkQuality};
use super::timing;
use super::uplink::{self, Uplink};
use super::version::{Band, BindingVersion};

/// Receiver settings (the parts of OpenLRSng's `rx_config` the link logic uses).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Generation to bind with; bind packets of the other one are refused.
    pub version: BindingVersion,
    /// Module band (binding frequency).
    pub band: Band,
    /// `failsafeDelay` in `delayInMs` code (default 10 = 1 s); 0 never applies failsafe.
    pub failsafe_delay: u8,
    /// Bind listening at boot when already bound (`ALWAYS_BIND`: 500 ms); `None` skips it.
    pub bind_window_us: Option<u32>,
}

impl Config {
    /// OpenLRSng's defaults: failsafe after 1 s, a 500 ms bind window at boot.
    pub const fn new(version: BindingVersion, band: Band) -> Self {
        Self {
            version,
            band,
            failsafe_delay: 10,
            bind_window_us: Some(500_000),
        }
    }
}

/// What the radio must do next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Program the bind configuration (`init_rfm(1)`) and listen.
    ListenBind,
    /// Program the link configuration (`init_rfm(0)`), tune hop index 0 and listen.
    StartLink(BindData),
    /// Tune this hop index (0x79 and the header byte) and listen again.
    Hop(u8),
}

/// What the application gets from a received packet.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Output {
    /// Nothing new (a repeated serial packet, an ignored bind-channel packet).
    Nothing,
    /// New bind data: persist it; the link starts with it.
    Bound(BindData),
    /// A bind packet that this RX refuses.
    BindRefused(BindReception),
    /// Channel values (10-bit). `save_failsafe` is set once per TX button press.
    Channels {
        /// `mode.channel_count()` values.
        channels_bits: Vec<u16, MAX_CHANNELS>,
        /// Store these values as failsafe.
        save_failsafe: bool,
    },
    /// New serial bytes for the RX UART.
    Serial(Vec<u8, 8>),
    /// A packet of a type we do not handle.
    Unknown(Uplink),
}

/// The RX's answer to one packet.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Reception {
    /// Send this now, on the same channel (the `'B'` ack or a 9-byte telemetry frame).
    pub reply: Option<Vec<u8, { telemetry::DOWNLINK_FRAME_LEN }>>,
    /// Then do this (after the reply has gone).
    pub command: Option<Command>,
    /// For the application.
    pub output: Output,
}

/// What a timer tick changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tick {
    /// Radio command, if any.
    pub command: Option<Command>,
    /// Failsafe has just started: apply the stored failsafe values.
    pub failsafe_started: bool,
}

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
}

impl Receiver {
    /// A receiver with optionally stored bind data (invalid or other-version data is ignored).
    pub fn new(config: Config, stored: Option<BindData>) -> Self {
        let data = stored.filter(|d| d.version == config.version.byte() && d.validate().is_ok());
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

    /// Radio readings for the next link-info frame: raw RSSI (0x26) and the 10-bit AFC
    /// correction (0x2B/0x2C), both sampled around the last packet.
    pub fn set_radio_measurements(&mut self, rssi: u8, afc: u16) {
        self.link_info.rssi = rssi;
        self.link_info.afc = afc;
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
                Some(failsafe_deadline.map_or(hop_deadline, |f| f.min(hop_deadline)))
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
        match bind::receive_bind_packet(packet, self.config.version) {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn bound() -> BindData {
        BindData::defaults(BindingVersion::V38, Band::Mhz433)
    }

    fn rc_packet(header: u8) -> Vec<u8, 11> {
        let mut p = Vec::new();
        p.extend_from_slice(&[header, 0, 1, 2, 3, 0, 4, 5, 6, 7, 0])
            .unwrap();
        p
    }

    #[test]
    fn stored_bind_data_gets_a_500_ms_bind_window_then_the_link() {
        let mut rx = Receiver::new(
            Config::new(BindingVersion::V38, Band::Mhz433),
            Some(bound()),
        );
        assert_eq!(rx.start(1_000), Command::ListenBind);
        assert_eq!(rx.next_deadline_us(), Some(501_000));
        assert_eq!(rx.poll(500_999).command, None);
        assert_eq!(rx.poll(501_000).command, Some(Command::StartLink(bound())));
        assert!(rx.is_linked());
        // Not acquired yet: slow hopping, one hop per interval · hopcount = 25 ms · 6.
        assert_eq!(rx.next_deadline_us(), Some(501_000 + 150_000 + 1));
        assert_eq!(rx.poll(651_001).command, Some(Command::Hop(1)));
    }

    #[test]
    fn other_generation_or_invalid_stored_data_means_binding_forever() {
        let mut other = bound();
        other.version = 0x39;
        let mut rx = Receiver::new(Config::new(BindingVersion::V38, Band::Mhz433), Some(other));
        assert_eq!(rx.start(0), Command::ListenBind);
        assert_eq!(rx.next_deadline_us(), None);
        assert_eq!(rx.poll(10_000_000).command, None);
    }

    #[test]
    fn save_failsafe_is_reported_once_per_press_and_lost_packets_hop_on_the_grid() {
        let config = Config {
            bind_window_us: None,
            ..Config::new(BindingVersion::V38, Band::Mhz433)
        };
        let mut rx = Receiver::new(config, Some(bound()));
        assert_eq!(rx.start(0), Command::StartLink(bound()));
        let saves: [bool; 4] = core::array::from_fn(|k| {
            let header = if k < 3 { 0x01 } else { 0x00 };
            let r = rx.on_packet(25_000 * k as u64, &rc_packet(header));
            assert!(
                r.reply.is_some(),
                "telemetry is on in the default bind data"
            );
            matches!(
                r.output,
                Output::Channels {
                    save_failsafe: true,
                    ..
                }
            )
        });
        assert_eq!(saves, [true, false, false, false]);
        assert_eq!(rx.hop_index(), 4);
        // Last packet at 75 ms: the next is missed 26 ms later, the hop follows the grid.
        assert_eq!(rx.next_deadline_us(), Some(75_000 + 26_000 + 1));
        assert_eq!(rx.poll(101_001).command, Some(Command::Hop(5)));
        assert_eq!(rx.next_deadline_us(), Some(100_000 + 26_000 + 1));
        // Four heard, one missed.
        assert_eq!(rx.link_quality(), 4);
    }
}
