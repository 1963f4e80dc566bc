//! The transmitter role as sans-IO state machines: the bind beacon (`bindMode()`) and the
//! link (`TX.h` loop): one uplink packet per interval on hop index n mod hopcount, RC and
//! serial interleaved, the downlink handshake and link quality (radio.md §1c "Hopping",
//! "Uplink", "Downlink"). Time is `now_us` from the caller.

use heapless::{Deque, Vec};

use super::bind::{self, BIND_PACKET_LEN, BindData};
use super::channels::{CENTER_BITS, MAX_CHANNELS};
use super::hopping;
use super::telemetry::{self, Downlink, LinkQuality};
use super::timing;
use super::uplink::{self, Packet};

/// Bind packets go out every 200 ms.
pub const BIND_PERIOD_US: u32 = 200_000;
/// After each bind packet the TX listens this long for the `'B'` reply.
pub const BIND_LISTEN_US: u32 = 50_000;

/// The TX in bind mode: sends the 42-byte bind packet every 200 ms until acknowledged.
#[derive(Debug, Clone)]
pub struct BindBeacon {
    packet: [u8; BIND_PACKET_LEN],
    next_send_us: u64,
    acknowledged: bool,
}

impl BindBeacon {
    /// Starts sending `data` at `now_us`.
    pub fn new(data: &BindData, now_us: u64) -> Self {
        Self {
            packet: data.bind_packet(),
            next_send_us: now_us,
            acknowledged: false,
        }
    }

    /// The bind packet to send now, if one is due (then listen [`BIND_LISTEN_US`]).
    pub fn poll(&mut self, now_us: u64) -> Option<&[u8; BIND_PACKET_LEN]> {
        if self.acknowledged || now_us < self.next_send_us {
            return None;
        }
        self.next_send_us = now_us + u64::from(BIND_PERIOD_US);
        Some(&self.packet)
    }

    /// When the next bind packet is due.
    pub fn next_deadline_us(&self) -> Option<u64> {
        (!self.acknowledged).then_some(self.next_send_us)
    }

    /// Feeds a packet heard while listening; returns whether it was the RX's `'B'`.
    pub fn on_packet(&mut self, packet: &[u8]) -> bool {
        if bind::is_bind_ack(packet) {
            self.acknowledged = true;
        }
        self.acknowledged
    }

    /// Whether an RX has acknowledged.
    pub fn acknowledged(&self) -> bool {
        self.acknowledged
    }
}

/// One uplink transmission.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Send {
    /// Tune this hop index first (0x79 and the header byte).
    pub hop_index: u8,
    /// Bytes for the FIFO.
    pub packet: Packet,
    /// Listen for the 9-byte reply on the same channel afterwards.
    pub expect_reply: bool,
}

/// What a downlink frame brought the TX.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Received {
    /// A repeat of a frame already processed.
    Duplicate,
    /// A new link report.
    LinkInfo(telemetry::LinkInfo),
    /// New serial bytes from the RX.
    Serial(Vec<u8, 8>),
    /// Not a frame we understand.
    Invalid(Downlink),
}

/// Capacity of the handset → uplink serial queue.
pub const SERIAL_QUEUE_LEN: usize = 64;

/// The TX on the link.
#[derive(Debug, Clone)]
pub struct Transmitter {
    data: BindData,
    interval_us: u32,
    hop_index: u8,
    next_send_us: u64,
    quality: LinkQuality,
    /// Our header bits: 7 = uplink serial sequence, 6 = downlink acknowledge.
    sequence_bits: u8,
    channels_bits: [u16; MAX_CHANNELS],
    save_failsafe: bool,
    serial_in: Deque<u8, SERIAL_QUEUE_LEN>,
    serial_unacked: Option<Vec<u8, 8>>,
    last_was_serial: bool,
    reply_since_rc: bool,
}

impl Transmitter {
    /// A transmitter for `data`, sending its first packet at `now_us`. `None` if the bind
    /// data is unusable (unknown modem profile, empty hop list).
    pub fn new(data: BindData, now_us: u64) -> Option<Self> {
        data.validate().ok()?;
        Some(Self {
            data,
            interval_us: timing::interval_us(&data)?,
            hop_index: 0,
            next_send_us: now_us,
            quality: LinkQuality(0),
            sequence_bits: 0,
            channels_bits: [CENTER_BITS; MAX_CHANNELS],
            save_failsafe: false,
            serial_in: Deque::new(),
            serial_unacked: None,
            last_was_serial: false,
            reply_since_rc: false,
        })
    }

    /// The bind data in use.
    pub fn bind_data(&self) -> &BindData {
        &self.data
    }

    /// The packet interval (µs).
    pub fn interval_us(&self) -> u32 {
        self.interval_us
    }

    /// Sets the channel values (10-bit) sent from the next packet on.
    pub fn set_channels(&mut self, channels_bits: &[u16]) {
        for (dst, &src) in self.channels_bits.iter_mut().zip(channels_bits) {
            *dst = src;
        }
    }

    /// While set, RC packets are type 0x01: the RX stores them as failsafe values.
    pub fn set_save_failsafe(&mut self, held: bool) {
        self.save_failsafe = held;
    }

    /// Queues handset serial bytes for the uplink; returns how many did not fit.
    pub fn queue_serial(&mut self, data: &[u8]) -> usize {
        data.iter()
            .filter(|&&b| self.serial_in.push_back(b).is_err())
            .count()
    }

    /// Downlink link quality 0..15 (replies heard over the last 15 completed slots).
    pub fn link_quality(&self) -> u8 {
        self.quality.tx_quality()
    }

    /// When the next packet is due.
    pub fn next_deadline_us(&self) -> u64 {
        self.next_send_us
    }

    /// The packet to send now, if one is due. Advance happens here: the caller sends it.
    pub fn poll(&mut self, now_us: u64) -> Option<Send> {
        if now_us < self.next_send_us {
            return None;
        }
        let interval = u64::from(self.interval_us);
        // Keep the grid; if we fell more than a slot behind, restart it from now.
        self.next_send_us = if now_us - self.next_send_us >= interval {
            now_us + interval
        } else {
            self.next_send_us + interval
        };
        let packet = self.next_packet();
        let hop_index = self.hop_index;
        self.hop_index = hopping::next_index(&self.data, self.hop_index);
        Some(Send {
            hop_index,
            packet,
            expect_reply: self.data.telemetry_enabled(),
        })
    }

    fn next_packet(&mut self) -> Packet {
        let size = self.data.channel_mode().packet_size();
        // Serial only after a reply confirmed the previous RC packet, never twice in a row.
        let may_send_serial =
            self.data.telemetry_enabled() && !self.last_was_serial && self.reply_since_rc;
        if may_send_serial {
            if self.serial_unacked.is_none() && !self.serial_in.is_empty() {
                let max = (size - 1).min(uplink::MAX_SERIAL_BYTES);
                let mut chunk: Vec<u8, 8> = Vec::new();
                while chunk.len() < max {
                    match self.serial_in.pop_front() {
                        Some(b) => {
                            let _ = chunk.push(b);
                        }
                        None => break,
                    }
                }
                self.sequence_bits ^= uplink::SEQ_UPLINK_SERIAL;
                self.serial_unacked = Some(chunk);
            }
            if let Some(packet) = self
                .serial_unacked
                .as_ref()
                .and_then(|chunk| uplink::serial_packet(self.sequence_bits, chunk, size))
            {
                self.last_was_serial = true;
                return packet;
            }
        }
        self.last_was_serial = false;
        self.reply_since_rc = false;
        let mode = self.data.channel_mode();
        uplink::servo_packet(
            mode,
            self.sequence_bits,
            self.save_failsafe,
            &self.channels_bits,
        )
        .unwrap_or_default()
    }

    /// The radio finished sending (`tx_done`): one more slot in the quality register.
    pub fn on_sent(&mut self) {
        self.quality.record(false);
    }

    /// Handles a 9-byte downlink frame heard after our packet.
    pub fn on_downlink(&mut self, frame: &[u8]) -> Received {
        let parsed = telemetry::parse(frame);
        let Some(&header) = frame
            .first()
            .filter(|_| !matches!(parsed, Downlink::WrongLength { .. }))
        else {
            return Received::Invalid(parsed);
        };
        self.quality.mark_heard();
        self.reply_since_rc = true;
        if self.serial_unacked.is_some()
            && (header ^ self.sequence_bits) & telemetry::SEQ_UPLINK_ACK == 0
        {
            self.serial_unacked = None;
        }
        if (header ^ self.sequence_bits) & telemetry::SEQ_DOWNLINK == 0 {
            return Received::Duplicate;
        }
        // Copying the RX's bit 6 is the acknowledgement.
        self.sequence_bits ^= uplink::SEQ_DOWNLINK_ACK;
        match parsed {
            Downlink::LinkInfo { info, .. } => Received::LinkInfo(info),
            Downlink::Serial { data, .. } => Received::Serial(data),
            other => Received::Invalid(other),
        }
    }
}
