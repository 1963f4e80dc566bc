//! Uplink (TX → RX) packets: header byte 0 with its sequence bits and type, servo packets,
//! the save-failsafe variant and serial-data packets 0x38..0x3F.

use heapless::Vec;

use super::channels::{self, ChannelMode, MAX_CHANNELS, MAX_PACKET_LEN};

/// Header bit 7: uplink serial sequence (toggled by the TX for each new serial payload).
pub const SEQ_UPLINK_SERIAL: u8 = 0x80;
/// Header bit 6: acknowledge of the last downlink frame (a copy of its bit 6).
pub const SEQ_DOWNLINK_ACK: u8 = 0x40;
/// Type 0x00: servo data.
pub const TYPE_SERVO: u8 = 0x00;
/// Type 0x01: servo data that the RX stores as its failsafe values.
pub const TYPE_SERVO_SAVE_FAILSAFE: u8 = 0x01;
/// Type 0x38 + (n − 1): n bytes of serial data (n = 1..8).
pub const TYPE_SERIAL_BASE: u8 = 0x38;
/// Most serial bytes one packet carries.
pub const MAX_SERIAL_BYTES: usize = 8;

/// An uplink packet, header byte first, as written to the TX FIFO.
pub type Packet = Vec<u8, MAX_PACKET_LEN>;

/// Builds a servo packet: `sequence_bits` (bits 7..6) | type 0x00 or 0x01, then the channels.
pub fn servo_packet(
    mode: ChannelMode,
    sequence_bits: u8,
    save_failsafe: bool,
    channels_bits: &[u16],
) -> Result<Packet, channels::Error> {
    let mut buf = [0u8; MAX_PACKET_LEN];
    let (header, payload) = buf.split_at_mut(1);
    let len = channels::pack(mode, channels_bits, payload)?;
    if let Some(h) = header.first_mut() {
        *h = (sequence_bits & 0xC0) | u8::from(save_failsafe);
    }
    // Fits: len + 1 <= MAX_PACKET_LEN by construction of the mode table.
    Vec::from_slice(buf.get(..=len).unwrap_or(&[]))
        .map_err(|_| channels::Error::BufferTooSmall { needed: len + 1 })
}

/// Builds a serial-data packet of the link's fixed `packet_size` carrying 1..8 bytes of
/// `data`; the unused tail is 0. Returns `None` for empty data or data that does not fit.
pub fn serial_packet(sequence_bits: u8, data: &[u8], packet_size: usize) -> Option<Packet> {
    if data.is_empty() || data.len() > MAX_SERIAL_BYTES || data.len() + 1 > packet_size {
        return None;
    }
    let header = (sequence_bits & 0xC0) | (TYPE_SERIAL_BASE + (data.len() as u8 - 1));
    let mut packet = Packet::new();
    packet.push(header).ok()?;
    packet.extend_from_slice(data).ok()?;
    packet.resize(packet_size, 0).ok()?;
    Some(packet)
}

/// What an uplink packet carries, as the RX classifies it (`(b0 & 0x3E) == 0` is servo).
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Uplink {
    /// Channel values in 10-bit form.
    Servo {
        /// Header bits 7..6.
        sequence_bits: u8,
        /// Type 0x01: store these values as failsafe.
        save_failsafe: bool,
        /// `mode.channel_count()` values.
        channels_bits: Vec<u16, MAX_CHANNELS>,
    },
    /// Serial bytes for the RX's UART.
    Serial {
        /// Header bits 7..6.
        sequence_bits: u8,
        /// 1..8 bytes.
        data: Vec<u8, MAX_SERIAL_BYTES>,
    },
    /// A type this implementation does not handle (dRonin placeholders, future types).
    Unknown {
        /// The header byte.
        header: u8,
    },
    /// The packet is shorter than its header promises.
    Truncated {
        /// Bytes received.
        len: usize,
    },
}

/// Classifies and decodes a received uplink packet.
pub fn parse(mode: ChannelMode, packet: &[u8]) -> Uplink {
    let Some((&header, payload)) = packet.split_first() else {
        return Uplink::Truncated { len: 0 };
    };
    let sequence_bits = header & 0xC0;
    if header & 0x3E == 0 {
        let mut values = [0u16; MAX_CHANNELS];
        return match channels::unpack(mode, payload, &mut values) {
            Ok(count) => Uplink::Servo {
                sequence_bits,
                save_failsafe: header & 0x01 != 0,
                channels_bits: values.iter().take(count).copied().collect(),
            },
            Err(_) => Uplink::Truncated { len: packet.len() },
        };
    }
    let kind = header & 0x3F;
    if kind >= TYPE_SERIAL_BASE {
        let n = usize::from(kind & 7) + 1;
        return match payload.get(..n) {
            Some(bytes) => Uplink::Serial {
                sequence_bits,
                data: bytes.iter().copied().collect(),
            },
            None => Uplink::Truncated { len: packet.len() },
        };
    }
    Uplink::Unknown { header }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serial_packet_is_padded_to_link_size() {
        let p = serial_packet(0x80, &[1, 2, 3], 11).unwrap();
        assert_eq!(p.as_slice(), &[0xBA, 1, 2, 3, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(
            parse(ChannelMode::from_flags(2), &p),
            Uplink::Serial {
                sequence_bits: 0x80,
                data: Vec::from_slice(&[1, 2, 3]).unwrap()
            }
        );
        assert_eq!(serial_packet(0, &[0; 9], 21), None);
    }

    #[test]
    fn save_failsafe_header() {
        let p = servo_packet(ChannelMode::from_flags(1), 0x40, true, &[512; 8]).unwrap();
        assert_eq!(p[0], 0x41);
        let Uplink::Servo {
            save_failsafe,
            sequence_bits,
            channels_bits,
        } = parse(ChannelMode::from_flags(1), &p)
        else {
            panic!("not servo")
        };
        assert!(save_failsafe);
        assert_eq!(sequence_bits, 0x40);
        assert_eq!(channels_bits[0], 512);
        assert_eq!(channels_bits[7], 678);
    }
}
