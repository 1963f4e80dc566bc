//! The packet handler's view of 0x30–0x4B: frame layout, header check, CRC and whitening.
//!
//! On air a frame is: preamble (prealen nibbles of 1010…), sync word (synclen+1 bytes from
//! 0x36), header (hdlen bytes from 0x3A, header 3 first), the length byte unless fixpklen,
//! the payload, and two CRC bytes when encrc (datasheet §6.2 "Packet Handler", Figure 31).
//! Whitening (PN9) covers everything after the sync word.

/// CRC polynomial selected by 0x30 crc\[1:0\].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CrcKind {
    /// 00: CCITT, x¹⁶+x¹²+x⁵+1 (0x1021).
    Ccitt,
    /// 01: CRC-16 (IBM), x¹⁶+x¹⁵+x²+1 (0x8005).
    Crc16Ibm,
    /// 10: IEC-16 (IEC 870-5, as used by wireless M-Bus), 0x3D65.
    Iec16,
    /// 11: "Biacheva" (Baicheva's CRC-16, 0xC86C in Koopman notation = 0x90D9;
    /// this model's reading of the datasheet name, not checked against silicon).
    Biacheva,
}

impl CrcKind {
    /// The generator polynomial without the x¹⁶ term.
    pub fn polynomial(self) -> u16 {
        match self {
            CrcKind::Ccitt => 0x1021,
            CrcKind::Crc16Ibm => 0x8005,
            CrcKind::Iec16 => 0x3D65,
            CrcKind::Biacheva => 0x90D9,
        }
    }

    /// CRC of `bytes`, MSB first, seed 0xFFFF, no final inversion (the model's assumption
    /// for the Si443x engine; both ends of the simulation use the same one).
    pub fn checksum(self, bytes: &[u8]) -> u16 {
        let mut crc = Crc16::new(self);
        for &b in bytes {
            crc.update(b);
        }
        crc.value()
    }
}

/// Bitwise running CRC-16 (cheap enough for a few bytes per event).
#[derive(Clone, Copy, Debug)]
pub struct Crc16 {
    polynomial: u16,
    value: u16,
}

impl Crc16 {
    /// A CRC seeded with 0xFFFF.
    pub fn new(kind: CrcKind) -> Self {
        Self {
            polynomial: kind.polynomial(),
            value: 0xFFFF,
        }
    }

    /// Feed one byte, MSB first.
    pub fn update(&mut self, byte: u8) {
        self.value ^= u16::from(byte) << 8;
        for _ in 0..8 {
            self.value = if self.value & 0x8000 != 0 {
                (self.value << 1) ^ self.polynomial
            } else {
                self.value << 1
            };
        }
    }

    /// The CRC so far.
    pub fn value(&self) -> u16 {
        self.value
    }
}

/// PN9 whitening sequence generator (x⁹ + x⁵ + 1, seed all ones), one byte at a time.
#[derive(Clone, Copy, Debug)]
pub struct Pn9 {
    state: u16,
}

impl Default for Pn9 {
    fn default() -> Self {
        Self { state: 0x1FF }
    }
}

impl Pn9 {
    /// The next 8 sequence bits, first bit in the MSB.
    pub fn next_byte(&mut self) -> u8 {
        let mut out = 0u8;
        for _ in 0..8 {
            let bit = (self.state & 1) as u8;
            out = (out << 1) | bit;
            let feedback = (self.state ^ (self.state >> 5)) & 1;
            self.state = (self.state >> 1) | (feedback << 8);
        }
        out
    }
}

/// The packet configuration decoded from one register file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PacketFormat {
    /// 0x30 enpacrx: packet handler in RX.
    pub handler_rx: bool,
    /// 0x30 enpactx: packet handler in TX.
    pub handler_tx: bool,
    /// CRC kind when 0x30 encrc is set.
    pub crc: Option<CrcKind>,
    /// 0x30 crcdonly: CRC over the payload only (else header + length + payload).
    pub crc_data_only: bool,
    /// Header bytes on air (0..=4), header 3 first.
    pub header_len: usize,
    /// 0x33 fixpklen: no length byte; both ends use 0x3E.
    pub fixed_length: bool,
    /// Sync word as sent (synclen + 1 bytes from 0x36).
    pub sync: Vec<u8>,
    /// Preamble length in nibbles (9 bits).
    pub preamble_nibbles: u16,
    /// Preamble detection threshold in nibbles (0x35 preath).
    pub preamble_threshold_nibbles: u8,
    /// 0x35 rssi_off (RSSI offset, ≈ 4 dB per step).
    pub rssi_offset: u8,
    /// Transmit headers 3..0 (0x3A–0x3D).
    pub tx_header: [u8; 4],
    /// 0x3E packet length.
    pub packet_length: u8,
    /// Check headers 3..0 (0x3F–0x42).
    pub check_header: [u8; 4],
    /// Header enable masks 3..0 (0x43–0x46).
    pub header_enable: [u8; 4],
    /// 0x32 bcen (bit i = header i accepts 0xFF).
    pub broadcast_enable: u8,
    /// 0x32 hdch (bit i = header i is checked).
    pub header_check: u8,
}

impl PacketFormat {
    /// Decode the packet-handler registers of `regs`.
    pub fn from_registers(regs: &[u8; 128]) -> Self {
        let r = |a: u8| regs.get(usize::from(a)).copied().unwrap_or(0);
        let dac = r(0x30);
        let hc2 = r(0x33);
        let four = |start: u8| [r(start), r(start + 1), r(start + 2), r(start + 3)];
        let sync_len = usize::from((hc2 >> 1) & 0x03) + 1;
        Self {
            handler_rx: dac & 0x80 != 0,
            handler_tx: dac & 0x08 != 0,
            crc: (dac & 0x04 != 0).then_some(match dac & 0x03 {
                0 => CrcKind::Ccitt,
                1 => CrcKind::Crc16Ibm,
                2 => CrcKind::Iec16,
                _ => CrcKind::Biacheva,
            }),
            crc_data_only: dac & 0x20 != 0,
            header_len: usize::from((hc2 >> 4) & 0x07).min(4),
            fixed_length: hc2 & 0x08 != 0,
            sync: four(0x36).iter().copied().take(sync_len).collect(),
            preamble_nibbles: (u16::from(hc2 & 0x01) << 8) | u16::from(r(0x34)),
            preamble_threshold_nibbles: r(0x35) >> 3,
            rssi_offset: r(0x35) & 0x07,
            tx_header: four(0x3A),
            packet_length: r(0x3E),
            check_header: four(0x3F),
            header_enable: four(0x43),
            broadcast_enable: r(0x32) >> 4,
            header_check: r(0x32) & 0x0F,
        }
    }

    /// Header bytes this end sends, in air order (header 3 first).
    pub fn tx_header_bytes(&self) -> &[u8] {
        self.tx_header.get(..self.header_len).unwrap_or(&[])
    }

    /// Whether a received header (air order, `header_len` bytes) passes 0x32/0x3F–0x46.
    pub fn header_accepted(&self, received: &[u8]) -> bool {
        received.iter().enumerate().all(|(k, &byte)| {
            // The k-th byte on air is header (3 − k); hdch/bcen bit i refers to header i.
            let bit = 1u8 << (3 - k.min(3));
            let check = self.check_header.get(k).copied().unwrap_or(0);
            let enable = self.header_enable.get(k).copied().unwrap_or(0);
            self.header_check & bit == 0
                || (byte ^ check) & enable == 0
                || (self.broadcast_enable & bit != 0 && byte == 0xFF)
        })
    }

    /// Bytes after the preamble for a `payload_len`-byte packet sent with this format.
    pub fn bytes_after_preamble(&self, payload_len: usize) -> usize {
        let (header, length, crc) = if self.handler_tx {
            (
                self.header_len,
                usize::from(!self.fixed_length),
                if self.crc.is_some() { 2 } else { 0 },
            )
        } else {
            (0, 0, 0)
        };
        self.sync.len() + header + length + payload_len + crc
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registers::reset_file;

    #[test]
    fn crc_check_values() {
        // "123456789" with seed 0xFFFF, MSB first, no inversion: CRC-16/CCITT-FALSE = 0x29B1,
        // CRC-16/CMS (poly 0x8005) = 0xAEE7.
        assert_eq!(CrcKind::Ccitt.checksum(b"123456789"), 0x29B1);
        assert_eq!(CrcKind::Crc16Ibm.checksum(b"123456789"), 0xAEE7);
        // The same engine with 0x3D65 and 0x90D9 (checked against an independent script).
        assert_eq!(CrcKind::Iec16.checksum(b"123456789"), 0xBBB6);
        assert_eq!(CrcKind::Biacheva.checksum(b"123456789"), 0x3778);
    }

    #[test]
    fn pn9_first_bytes() {
        // PN9 seeded with all ones, LSB out, feedback bit0 ^ bit5 into bit 8: the first nine
        // output bits are the seed (all ones), then the feedback pattern.
        let mut pn9 = Pn9::default();
        assert_eq!(pn9.next_byte(), 0xFF);
        assert_eq!(pn9.next_byte(), 0x87);
        // The sequence has period 511 bits, so 511 bytes later it repeats.
        let mut a = Pn9::default();
        let first: Vec<u8> = (0..4).map(|_| a.next_byte()).collect();
        let mut b = Pn9::default();
        for _ in 0..511 {
            b.next_byte();
        }
        let again: Vec<u8> = (0..4).map(|_| b.next_byte()).collect();
        assert_eq!(first, again);
    }

    #[test]
    fn reset_format_and_tau_labs_format() {
        let f = PacketFormat::from_registers(&reset_file());
        assert_eq!(f.sync, vec![0x2D, 0xD4]);
        assert_eq!(f.header_len, 2);
        assert_eq!(f.crc, Some(CrcKind::Crc16Ibm));
        assert_eq!(f.preamble_nibbles, 8);
        assert_eq!(f.preamble_threshold_nibbles, 5);
        assert_eq!(f.bytes_after_preamble(10), 2 + 2 + 1 + 10 + 2);

        let mut regs = reset_file();
        for (a, v) in [
            (0x30u8, 0x88u8),
            (0x33, 0x46),
            (0x34, 0x0C),
            (0x35, 0x30),
            (0x32, 0xFF),
            (0x36, 0x2D),
            (0x37, 0xD4),
            (0x38, 0x4B),
            (0x39, 0x59),
        ] {
            regs[usize::from(a)] = v;
        }
        regs[0x3F..0x43].copy_from_slice(&[0x12, 0x34, 0x56, 0x78]);
        let f = PacketFormat::from_registers(&regs);
        assert_eq!(f.sync, vec![0x2D, 0xD4, 0x4B, 0x59]);
        assert_eq!(f.header_len, 4);
        assert_eq!(f.crc, None);
        assert_eq!(f.bytes_after_preamble(16), 4 + 4 + 1 + 16);
        assert!(f.header_accepted(&[0x12, 0x34, 0x56, 0x78]));
        assert!(f.header_accepted(&[0xFF, 0xFF, 0xFF, 0xFF]));
        assert!(!f.header_accepted(&[0x12, 0x34, 0x56, 0x79]));
    }

    #[test]
    fn header_enable_masks_bits() {
        let mut regs = reset_file();
        regs[0x32] = 0x08; // check header 3 only, no broadcast
        regs[0x33] = 0x42;
        regs[0x3F] = 0xA5;
        regs[0x43] = 0xF0; // only the high nibble counts
        let f = PacketFormat::from_registers(&regs);
        assert!(f.header_accepted(&[0xA0, 0, 0, 0]));
        assert!(f.header_accepted(&[0xAF, 9, 9, 9]));
        assert!(!f.header_accepted(&[0xB5, 0, 0, 0]));
        assert!(!f.header_accepted(&[0xFF, 0, 0, 0]));
    }
}
