//! The downlink (RX → TX): the 9-byte link-info frame, serial-data frames 0x38..0x3F, link
//! quality shift registers and the composite RSSI scale.

use heapless::Vec;

/// `TELEMETRY_PACKETSIZE`: every downlink packet is 9 bytes.
pub const DOWNLINK_FRAME_LEN: usize = 9;
/// Header bit 7: acknowledge of the uplink serial sequence.
pub const SEQ_UPLINK_ACK: u8 = 0x80;
/// Header bit 6: downlink sequence, toggled for each new frame.
pub const SEQ_DOWNLINK: u8 = 0x40;
/// Serial bytes one downlink frame carries at most.
pub const MAX_SERIAL_BYTES: usize = 8;

/// A downlink packet.
pub type Frame = [u8; DOWNLINK_FRAME_LEN];

/// The RX's link report (type 0x00).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkInfo {
    /// Raw Si4432 RSSI (register 0x26) last sampled by the RX.
    pub rssi: u8,
    /// Analog input 0 (>> 2).
    pub analog0: u8,
    /// Analog input 1 (>> 2).
    pub analog1: u8,
    /// 10-bit AFC correction (registers 0x2B/0x2C).
    pub afc: u16,
    /// Uplink link quality 0..15.
    pub link_quality: u8,
}

/// `countSetBits`.
pub const fn count_set_bits(x: u16) -> u8 {
    x.count_ones() as u8
}

/// Builds a link-info frame: `[seq][RSSI][AIN0][AIN1][AFC hi][AFC lo][LQ][0][0]`. The last
/// two bytes are stale buffer contents upstream; we send 0.
pub fn link_info_frame(sequence_bits: u8, info: &LinkInfo) -> Frame {
    let [afc_hi, afc_lo] = info.afc.to_be_bytes();
    [
        sequence_bits & 0xC0,
        info.rssi,
        info.analog0,
        info.analog1,
        afc_hi,
        afc_lo,
        info.link_quality,
        0,
        0,
    ]
}

/// Builds a serial frame with 1..8 bytes: header `seq | (0x37 + n)`; `None` otherwise.
pub fn serial_frame(sequence_bits: u8, data: &[u8]) -> Option<Frame> {
    if data.is_empty() || data.len() > MAX_SERIAL_BYTES {
        return None;
    }
    let mut frame = [0u8; DOWNLINK_FRAME_LEN];
    let (header, body) = frame.split_at_mut(1);
    for (slot, &b) in body.iter_mut().zip(data) {
        *slot = b;
    }
    if let Some(h) = header.first_mut() {
        *h = (sequence_bits & 0xC0) | (0x37 + data.len() as u8);
    }
    Some(frame)
}

/// What a downlink frame carries.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Downlink {
    /// Type 0x00.
    LinkInfo {
        /// Header bits 7..6.
        sequence_bits: u8,
        /// The report.
        info: LinkInfo,
    },
    /// Types 0x38..0x3F.
    Serial {
        /// Header bits 7..6.
        sequence_bits: u8,
        /// 1..8 bytes.
        data: Vec<u8, MAX_SERIAL_BYTES>,
    },
    /// Any other type.
    Unknown {
        /// The header byte.
        header: u8,
    },
    /// Not 9 bytes.
    WrongLength {
        /// Bytes received.
        len: usize,
    },
}

/// Decodes a downlink frame received by the TX.
pub fn parse(frame: &[u8]) -> Downlink {
    let Ok(&[header, b1, b2, b3, b4, b5, b6, _, _]) = <&Frame>::try_from(frame) else {
        return Downlink::WrongLength { len: frame.len() };
    };
    let sequence_bits = header & 0xC0;
    match header & 0x3F {
        0x00 => Downlink::LinkInfo {
            sequence_bits,
            info: LinkInfo {
                rssi: b1,
                analog0: b2,
                analog1: b3,
                afc: u16::from_be_bytes([b4, b5]),
                link_quality: b6,
            },
        },
        kind @ 0x38..=0x3F => Downlink::Serial {
            sequence_bits,
            data: frame
                .iter()
                .skip(1)
                .take(usize::from(kind - 0x37))
                .copied()
                .collect(),
        },
        _ => Downlink::Unknown { header },
    }
}

/// A 16-slot link-quality shift register: 1 per packet heard, 0 per slot missed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkQuality(pub u16);

impl LinkQuality {
    /// Shifts in one slot.
    pub fn record(&mut self, heard: bool) {
        self.0 = (self.0 << 1) | u16::from(heard);
    }

    /// Marks the newest slot as heard (the TX ORs 1 in when a reply arrives).
    pub fn mark_heard(&mut self) {
        self.0 |= 1;
    }

    /// RX link quality: set bits of the last 15 slots (`& 0x7FFF`), 0..15.
    pub fn rx_quality(self) -> u8 {
        count_set_bits(self.0 & 0x7FFF)
    }

    /// TX link quality: set bits of the 15 completed slots (`& 0xFFFE`), 0..15.
    pub fn tx_quality(self) -> u8 {
        count_set_bits(self.0 & 0xFFFE)
    }
}

/// The RX's RSSI sampling (RX.h): one reading per slot, taken `interval − 1500 µs` after the
/// last packet — while the next packet is on air — and only while at most one packet has
/// been missed. Every 9 readings are averaged into `smooth = (3·smooth + avg) / 4`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RssiSampler {
    sampled_for_us: Option<u64>,
    sum: u16,
    count: u8,
    last: u8,
    smooth: u8,
}

impl RssiSampler {
    /// When the next reading is due, if one is (`last_packet_us` is the expected-packet
    /// grid the RX keeps, which moves on by one interval per missed packet).
    pub fn due_us(&self, last_packet_us: u64, interval_us: u32, lost_packets: u8) -> Option<u64> {
        (lost_packets < 2 && self.sampled_for_us != Some(last_packet_us))
            .then(|| last_packet_us + u64::from(interval_us.saturating_sub(1500)) + 1)
    }

    /// Whether to read RSSI now; marks this slot as sampled when it says yes.
    pub fn take_due(
        &mut self,
        now_us: u64,
        last_packet_us: u64,
        interval_us: u32,
        lost_packets: u8,
    ) -> bool {
        match self.due_us(last_packet_us, interval_us, lost_packets) {
            Some(due) if now_us >= due => {
                self.sampled_for_us = Some(last_packet_us);
                true
            }
            _ => false,
        }
    }

    /// Adds a reading of register 0x26.
    pub fn record(&mut self, rssi: u8) {
        self.last = rssi;
        self.sum += u16::from(rssi);
        self.count += 1;
        if self.count > 8 {
            let average = self.sum / u16::from(self.count);
            self.smooth = ((u16::from(self.smooth) * 3 + average) / 4) as u8;
            self.sum = 0;
            self.count = 0;
        }
    }

    /// The last reading (what the link-info frame reports).
    pub fn last(&self) -> u8 {
        self.last
    }

    /// The smoothed RSSI (for RSSI outputs and injection).
    pub fn smoothed(&self) -> u8 {
        self.smooth
    }
}

/// `compositeRSSI`: at full quality (≥ 15) the RSSI maps to 128..255, otherwise the quality
/// alone maps to 0..126 in steps of 9 — one scale that degrades gracefully.
pub const fn composite_rssi(link_quality: u8, rssi: u8) -> u8 {
    if link_quality >= 15 {
        (rssi >> 1) + 128
    } else {
        link_quality.saturating_mul(9)
    }
}

/// `RSSI2Bits`: RSSI injected into a servo channel, `clamp(rssi · 4, 12, 1012)`.
pub const fn rssi_to_bits(rssi: u8) -> u16 {
    let v = rssi as u16 * 4;
    if v < 12 {
        12
    } else if v > 1012 {
        1012
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn link_info_round_trip() {
        let info = LinkInfo {
            rssi: 200,
            analog0: 1,
            analog1: 2,
            afc: 0x3FF,
            link_quality: 15,
        };
        let f = link_info_frame(0x40, &info);
        assert_eq!(f, [0x40, 200, 1, 2, 0x03, 0xFF, 15, 0, 0]);
        assert_eq!(
            parse(&f),
            Downlink::LinkInfo {
                sequence_bits: 0x40,
                info
            }
        );
        assert_eq!(parse(&f[..8]), Downlink::WrongLength { len: 8 });
    }

    #[test]
    fn quality_register() {
        let mut lq = LinkQuality(0);
        for _ in 0..20 {
            lq.record(true);
        }
        lq.record(false);
        assert_eq!(lq.rx_quality(), 14);
        assert_eq!(lq.tx_quality(), 15);
        assert_eq!(composite_rssi(15, 100), 178);
        assert_eq!(composite_rssi(3, 100), 27);
    }

    #[test]
    fn rssi_sampler_once_per_slot_and_smoothing() {
        let mut r = RssiSampler::default();
        assert_eq!(r.due_us(100_000, 25_000, 0), Some(123_501));
        assert!(!r.take_due(123_500, 100_000, 25_000, 0));
        assert!(r.take_due(123_501, 100_000, 25_000, 0));
        assert!(!r.take_due(124_000, 100_000, 25_000, 0), "once per slot");
        assert_eq!(r.due_us(125_000, 25_000, 2), None, "not after two misses");
        for _ in 0..9 {
            r.record(200);
        }
        assert_eq!((r.last(), r.smoothed()), (200, 50));
        for _ in 0..9 {
            r.record(200);
        }
        assert_eq!(r.smoothed(), 87);
    }
}
