//! The transmitter role as sans-IO state machines: the bind beacon (`bindMode()`) and the
//! link (`TX.h` loop): one uplink packet per interval on hop index n mod hopcount, RC and
//! serial interleaved, the downlink handshake and link quality. Time is `now_us` from the caller.

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
/// OpenLRSng stops sending when its input is older than this many packets (`ppmAge`).
pub const STALE_INPUT_PACKETS: u8 = 8;

/// The uplink serial handshake (`serial_okToSend` in TX.h): serial goes out only after a
/// reply confirmed an RC packet, and an unanswered serial packet is repeated after the
/// next RC packet, so RC keeps at least half the packet rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SerialState {
    /// 0: an RC packet must go first.
    NeedRc,
    /// 1: an RC packet went out; waiting for its reply.
    RcSent,
    /// 2: a reply confirmed the RC packet; serial may go.
    Ready,
    /// 3: serial sent, not yet answered.
    Unanswered,
    /// 4: the serial packet went unanswered; repeat it in the next slot.
    Resend,
}

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
    serial_last: Vec<u8, 8>,
    serial_state: SerialState,
    /// Packets sent since the last input frame; `None` when input age is not enforced.
    input_age: Option<u8>,
}

impl Transmitter {
    /// A transmitter for `data`, sending its first packet at `now_us`.
    pub fn new(data: BindData, now_us: u64) -> Result<Self, bind::Error> {
        data.validate()?;
        let interval_us =
            timing::interval_us(&data).ok_or(bind::Error::ModemProfile(data.modem_profile))?;
        Ok(Self {
            data,
            interval_us,
            hop_index: 0,
            next_send_us: now_us,
            quality: LinkQuality(0),
            sequence_bits: 0,
            channels_bits: [CENTER_BITS; MAX_CHANNELS],
            save_failsafe: false,
            serial_in: Deque::new(),
            serial_last: Vec::new(),
            serial_state: SerialState::NeedRc,
            input_age: None,
        })
    }

    /// Stop sending while the input is stale, as OpenLRSng does when `minch` ≠ 0 (its
    /// default): nothing goes out before the first [`Transmitter::set_channels`], nor once 8
    /// packets have been sent without a new one, so the RX enters failsafe when the handset
    /// stops. The grid keeps running and the hop index stays where it was.
    pub fn with_stale_input_stop(mut self) -> Self {
        self.input_age = Some(u8::MAX);
        self
    }

    /// The bind data in use.
    pub fn bind_data(&self) -> &BindData {
        &self.data
    }

    /// The packet interval (µs).
    pub fn interval_us(&self) -> u32 {
        self.interval_us
    }

    /// A new input frame: the channel values (10-bit) sent from the next packet on.
    pub fn set_channels(&mut self, channels_bits: &[u16]) {
        for (dst, &src) in self.channels_bits.iter_mut().zip(channels_bits) {
            *dst = src;
        }
        if let Some(age) = self.input_age.as_mut() {
            *age = 0;
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

    /// Bytes [`Transmitter::queue_serial`] still takes whole.
    pub fn serial_free(&self) -> usize {
        self.serial_in.capacity() - self.serial_in.len()
    }

    /// Downlink link quality 0..15 (replies heard over the last 15 completed slots).
    pub fn link_quality(&self) -> u8 {
        self.quality.tx_quality()
    }

    /// When the next packet is due.
    pub fn next_deadline_us(&self) -> u64 {
        self.next_send_us
    }

    /// The packet to send now, if one is due; the caller sends it.
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
        if let Some(age) = self.input_age.as_mut() {
            if *age >= STALE_INPUT_PACKETS {
                return None;
            }
            *age += 1;
        }
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
        let serial = match self.serial_state {
            SerialState::Ready if !self.serial_in.is_empty() => {
                // New data: toggle bit 7 so the RX knows it is not a repeat.
                self.sequence_bits ^= uplink::SEQ_UPLINK_SERIAL;
                let max = (size - 1).min(uplink::MAX_SERIAL_BYTES);
                self.serial_last.clear();
                while self.serial_last.len() < max {
                    match self.serial_in.pop_front() {
                        Some(b) => {
                            let _ = self.serial_last.push(b);
                        }
                        None => break,
                    }
                }
                true
            }
            // A repeat keeps bit 7, so an RX that did get it drops the copy.
            SerialState::Resend => true,
            _ => false,
        };
        if serial
            && let Some(packet) = uplink::serial_packet(self.sequence_bits, &self.serial_last, size)
        {
            self.serial_state = SerialState::Unanswered;
            return packet;
        }
        if !self.save_failsafe {
            self.serial_state = match self.serial_state {
                SerialState::NeedRc => SerialState::RcSent,
                SerialState::Unanswered => SerialState::Resend,
                other => other,
            };
        }
        let mode = self.data.channel_mode();
        uplink::servo_packet(
            mode,
            self.sequence_bits,
            self.save_failsafe,
            &self.channels_bits,
        )
        .unwrap_or_default()
    }

    /// The radio finished sending (`tx_done`): with telemetry on, one more slot in the
    /// quality register, to be marked when the reply arrives.
    pub fn on_sent(&mut self) {
        if self.data.telemetry_enabled() {
            self.quality.record(false);
        }
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
        self.serial_state = match self.serial_state {
            SerialState::RcSent => SerialState::Ready,
            // Any reply to the serial packet acknowledges it.
            SerialState::Unanswered => SerialState::NeedRc,
            other => other,
        };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BindingVersion, RfmType};

    fn link() -> Transmitter {
        // 8 channels + serial telemetry, 25 ms.
        Transmitter::new(BindData::defaults(BindingVersion::V38, RfmType::Mhz433), 0).unwrap()
    }

    fn reply(tx: &mut Transmitter, header: u8) -> Received {
        tx.on_downlink(&[header, 0, 0, 0, 0, 0, 0, 0, 0])
    }

    #[test]
    fn serial_waits_for_a_confirmed_rc_packet_and_repeats_when_unanswered() {
        let mut tx = link();
        tx.queue_serial(b"abc");
        let first = tx.poll(0).unwrap();
        assert_eq!(first.packet[0] & 0x3F, 0x00, "RC first");
        assert_eq!(
            reply(&mut tx, 0x40),
            Received::LinkInfo(telemetry::LinkInfo {
                rssi: 0,
                analog0: 0,
                analog1: 0,
                afc: 0,
                link_quality: 0
            })
        );
        let serial = tx.poll(25_000).unwrap();
        // Bit 7 toggled for new data, bit 6 acknowledges the RX's frame, 3 bytes.
        assert_eq!(&serial.packet[..4], &[0xC0 | 0x3A, b'a', b'b', b'c']);
        assert_eq!(serial.hop_index, 1);
        // No reply: RC goes next, then the same serial packet again.
        assert_eq!(tx.poll(50_000).unwrap().packet[0], 0xC0);
        assert_eq!(
            &tx.poll(75_000).unwrap().packet[..4],
            &[0xFA, b'a', b'b', b'c']
        );
        assert_eq!(reply(&mut tx, 0x40), Received::Duplicate);
        assert_eq!(tx.poll(100_000).unwrap().packet[0], 0xC0);
    }

    #[test]
    fn stale_input_stops_the_uplink_without_hopping() {
        let mut tx = link().with_stale_input_stop();
        assert_eq!(tx.poll(0), None, "nothing before the first input frame");
        tx.set_channels(&[512; 8]);
        let sent: usize = (1..=12).filter(|k| tx.poll(k * 25_000).is_some()).count();
        assert_eq!(sent, 8);
        tx.set_channels(&[600; 8]);
        assert_eq!(tx.poll(13 * 25_000).unwrap().hop_index, 8 % 6);
    }
}
