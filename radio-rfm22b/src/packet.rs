//! The packet handler's configuration (registers 0x30–0x46; datasheet "Packet Handler"):
//! preamble, sync word, header and its checks, CRC, fixed or variable length, whitening.
//! Pure and `const`; the driver writes its register blocks.

use crate::ConfigError;
use crate::modem::ModemConfig;

/// The hardware CRC (0x30 bits 2:0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Crc {
    /// No CRC: every received packet is "valid" (Tau Labs relies on its own RS code).
    Off,
    /// CCITT (x^16 + x^12 + x^5 + 1), what OpenLRSng uses.
    Ccitt,
    /// CRC-16 (IBM, x^16 + x^15 + x^2 + 1).
    Crc16,
    /// IEC-16.
    Iec16,
    /// Biacheva.
    Biacheva,
}

impl Crc {
    const fn bits(self) -> u8 {
        match self {
            Crc::Off => 0x00,
            Crc::Ccitt => 0x04,
            Crc::Crc16 => 0x05,
            Crc::Iec16 => 0x06,
            Crc::Biacheva => 0x07,
        }
    }
}

/// How the packet length is conveyed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PacketLength {
    /// A length byte follows the header on air (1–255 bytes per packet).
    Variable,
    /// Every packet has this many bytes; no length byte is sent.
    Fixed(u8),
}

/// Packet-handler settings. Start from [`PacketConfig::new`] and adjust with the `with_*`
/// methods; the driver validates it once in `configure`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PacketConfig {
    preamble_nibbles: u16,
    preamble_threshold_nibbles: u8,
    rssi_offset: u8,
    sync_word: [u8; 4],
    sync_len: u8,
    header: [u8; 4],
    header_len: u8,
    check_header: [u8; 4],
    header_enable: [u8; 4],
    header_check_bytes: u8,
    broadcast_bytes: u8,
    crc: Crc,
    length: PacketLength,
    whitening: bool,
}

impl Default for PacketConfig {
    fn default() -> Self {
        Self::new()
    }
}

impl PacketConfig {
    /// 40-bit preamble, 20-bit detection threshold (the datasheet's recommendation for
    /// AFC on), sync word `2D D4`, no header, CRC-CCITT, variable length, no whitening.
    pub const fn new() -> Self {
        Self {
            preamble_nibbles: 10,
            preamble_threshold_nibbles: 5,
            rssi_offset: 0,
            sync_word: [0x2D, 0xD4, 0x00, 0x00],
            sync_len: 2,
            header: [0; 4],
            header_len: 0,
            check_header: [0; 4],
            header_enable: [0xFF; 4],
            header_check_bytes: 0,
            broadcast_bytes: 0,
            crc: Crc::Ccitt,
            length: PacketLength::Variable,
            whitening: false,
        }
    }

    /// TX preamble length and RX detection threshold, both in nibbles (4 bits).
    pub const fn with_preamble(mut self, length_nibbles: u16, threshold_nibbles: u8) -> Self {
        self.preamble_nibbles = length_nibbles;
        self.preamble_threshold_nibbles = threshold_nibbles;
        self
    }

    /// 0x35 rssi_off (0–7): shifts the RSSI reading up by about 4 dB per step.
    pub const fn with_rssi_offset(mut self, rssi_offset: u8) -> Self {
        self.rssi_offset = rssi_offset;
        self
    }

    /// The sync word: the first `len` (1–4) bytes of `word`, first on air first.
    pub const fn with_sync_word(mut self, word: [u8; 4], len: u8) -> Self {
        self.sync_word = word;
        self.sync_len = len;
        self
    }

    /// The transmitted header: the first `len` (0–4) bytes of `header`, first on air first.
    pub const fn with_header(mut self, header: [u8; 4], len: u8) -> Self {
        self.header = header;
        self.header_len = len;
        self
    }

    /// Replaces the transmitted header bytes, keeping its length (run-time changes go through
    /// the stored configuration so a re-init after a reset keeps them).
    pub(crate) const fn set_header_bytes(&mut self, header: [u8; 4]) {
        self.header = header;
    }

    /// Replaces the expected header bytes, keeping the masks.
    pub(crate) const fn set_check_header_bytes(&mut self, expected: [u8; 4]) {
        self.check_header = expected;
    }

    /// Receive-side header filter. `check_bytes` / `broadcast_bytes` are 4-bit masks (bit 3 =
    /// the first header byte on air): a checked byte must equal `expected & enable`, or be 0xFF
    /// if broadcast is on for it. `enable` masks the bits compared in each byte.
    pub const fn with_header_check(
        mut self,
        expected: [u8; 4],
        enable: [u8; 4],
        check_bytes: u8,
        broadcast_bytes: u8,
    ) -> Self {
        self.check_header = expected;
        self.header_enable = enable;
        self.header_check_bytes = check_bytes;
        self.broadcast_bytes = broadcast_bytes;
        self
    }

    /// The hardware CRC.
    pub const fn with_crc(mut self, crc: Crc) -> Self {
        self.crc = crc;
        self
    }

    /// Fixed or variable length.
    pub const fn with_length(mut self, length: PacketLength) -> Self {
        self.length = length;
        self
    }

    /// PN9 data whitening (0x70 bit 0).
    pub const fn with_whitening(mut self, whitening: bool) -> Self {
        self.whitening = whitening;
        self
    }

    /// Checks every field against what the registers can hold.
    pub const fn validate(&self) -> Result<(), ConfigError> {
        if self.preamble_nibbles == 0
            || self.preamble_nibbles > 0x1FF
            || self.preamble_threshold_nibbles == 0
            || self.preamble_threshold_nibbles > 31
            || self.rssi_offset > 7
        {
            return Err(ConfigError::InvalidPreamble);
        }
        if self.sync_len == 0 || self.sync_len > 4 {
            return Err(ConfigError::InvalidSyncWord);
        }
        if self.header_len > 4 {
            return Err(ConfigError::InvalidHeader);
        }
        // Only bytes that are sent can be checked: header 3 (bit 3) first, then 2, 1, 0.
        let present = (0xF0u8 >> self.header_len) & 0x0F;
        if self.header_check_bytes & !present != 0 || self.broadcast_bytes & !present != 0 {
            return Err(ConfigError::InvalidHeader);
        }
        if let PacketLength::Fixed(0) = self.length {
            return Err(ConfigError::InvalidLength);
        }
        Ok(())
    }

    /// The CRC setting.
    pub const fn crc(&self) -> Crc {
        self.crc
    }

    /// The length mode.
    pub const fn length(&self) -> PacketLength {
        self.length
    }

    /// Whether whitening is on (the driver ORs it into 0x70).
    pub const fn whitening(&self) -> bool {
        self.whitening
    }

    /// 0x35 rssi_off.
    pub const fn rssi_offset(&self) -> u8 {
        self.rssi_offset
    }

    /// Register 0x30 (packet handler on for RX and TX, MSB first).
    pub const fn data_access_control(&self) -> u8 {
        0x80 | 0x08 | self.crc.bits()
    }

    /// Registers 0x32–0x35.
    pub const fn header_block(&self) -> [u8; 4] {
        let fixed = matches!(self.length, PacketLength::Fixed(_));
        [
            (self.broadcast_bytes << 4) | self.header_check_bytes,
            (self.header_len << 4)
                | (if fixed { 0x08 } else { 0 })
                | ((self.sync_len.saturating_sub(1) & 0x03) << 1)
                | ((self.preamble_nibbles >> 8) as u8 & 0x01),
            self.preamble_nibbles as u8,
            (self.preamble_threshold_nibbles << 3) | self.rssi_offset,
        ]
    }

    /// Registers 0x36–0x46: sync word, TX header, length, check header, header enables.
    pub const fn address_block(&self) -> [u8; 17] {
        let s = self.sync_word;
        let h = self.header;
        let c = self.check_header;
        let e = self.header_enable;
        let len = match self.length {
            PacketLength::Fixed(n) => n,
            PacketLength::Variable => 0,
        };
        [
            s[0], s[1], s[2], s[3], h[0], h[1], h[2], h[3], len, c[0], c[1], c[2], c[3], e[0],
            e[1], e[2], e[3],
        ]
    }

    /// Time on air of a packet with `payload_len` bytes, in microseconds (rounded up).
    pub const fn airtime_us(&self, modem: &ModemConfig, payload_len: u8) -> u32 {
        let mut bits = self.preamble_nibbles as u32 * 4
            + self.sync_len as u32 * 8
            + self.header_len as u32 * 8
            + payload_len as u32 * 8;
        if matches!(self.length, PacketLength::Variable) {
            bits += 8;
        }
        if !matches!(self.crc, Crc::Off) {
            bits += 16;
        }
        // Manchester sends two chips per data bit: the air time doubles (the TX data-rate
        // register holds the data rate, the receiver's clock recovery the chip rate).
        if modem.settings().manchester {
            bits *= 2;
        }
        // A modem at 0 bit/s cannot be built; 1 keeps the division free of a panic path.
        let rate = match modem.bit_rate_bps() as u64 {
            0 => 1,
            r => r,
        };
        ((bits as u64 * 1_000_000).div_ceil(rate)) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn openlrsng_packet_registers() {
        // OpenLRSng init_rfm: 0x30=8C 0x32=0F 0x33=42 0x34=0A 0x35=2A, sync 2D D4.
        let magic = [0xDE, 0xAD, 0xFE, 0xED];
        let p = PacketConfig::new()
            .with_preamble(10, 5)
            .with_rssi_offset(2)
            .with_header(magic, 4)
            .with_header_check(magic, [0xFF; 4], 0x0F, 0x00);
        p.validate().unwrap();
        assert_eq!(p.data_access_control(), 0x8C);
        assert_eq!(p.header_block(), [0x0F, 0x42, 0x0A, 0x2A]);
        let a = p.address_block();
        assert_eq!(a[..4], [0x2D, 0xD4, 0x00, 0x00]);
        assert_eq!(a[4..8], magic);
        assert_eq!(a[9..13], magic);
    }

    #[test]
    fn taulabs_packet_registers() {
        // Tau Labs rfm22_init: 0x30=88 0x32=FF 0x33=46 0x34=0C 0x35=30, sync 2D D4 4B 59.
        let p = PacketConfig::new()
            .with_preamble(12, 6)
            .with_sync_word([0x2D, 0xD4, 0x4B, 0x59], 4)
            .with_header([1, 2, 3, 4], 4)
            .with_header_check([1, 2, 3, 4], [0xFF; 4], 0x0F, 0x0F)
            .with_crc(Crc::Off)
            .with_whitening(true);
        assert_eq!(p.data_access_control(), 0x88);
        assert_eq!(p.header_block(), [0xFF, 0x46, 0x0C, 0x30]);
        assert_eq!(p.address_block()[..4], [0x2D, 0xD4, 0x4B, 0x59]);
    }

    #[test]
    fn fixed_length_long_preamble_and_crcs() {
        let p = PacketConfig::new()
            .with_preamble(300, 8)
            .with_length(PacketLength::Fixed(20))
            .with_crc(Crc::Biacheva);
        assert_eq!(p.header_block(), [0x00, 0x0B, 0x2C, 0x40]);
        assert_eq!(p.data_access_control(), 0x8F);
        assert_eq!(p.address_block()[8], 20);
        assert_eq!(
            PacketConfig::new()
                .with_crc(Crc::Crc16)
                .data_access_control(),
            0x8D
        );
        assert_eq!(
            PacketConfig::new()
                .with_crc(Crc::Iec16)
                .data_access_control(),
            0x8E
        );
    }

    #[test]
    fn invalid_settings_are_rejected() {
        assert_eq!(
            PacketConfig::new().with_preamble(0, 5).validate(),
            Err(ConfigError::InvalidPreamble)
        );
        assert_eq!(
            PacketConfig::new().with_preamble(512, 5).validate(),
            Err(ConfigError::InvalidPreamble)
        );
        assert_eq!(
            PacketConfig::new().with_preamble(8, 32).validate(),
            Err(ConfigError::InvalidPreamble)
        );
        assert_eq!(
            PacketConfig::new().with_sync_word([0; 4], 5).validate(),
            Err(ConfigError::InvalidSyncWord)
        );
        assert_eq!(
            PacketConfig::new().with_header([0; 4], 5).validate(),
            Err(ConfigError::InvalidHeader)
        );
        // Checking header byte 1 while only bytes 3 and 2 are sent.
        let two = PacketConfig::new().with_header([7, 8, 0, 0], 2);
        assert!(
            two.with_header_check([7, 8, 0, 0], [0xFF; 4], 0x0C, 0)
                .validate()
                .is_ok()
        );
        assert_eq!(
            two.with_header_check([7, 8, 0, 0], [0xFF; 4], 0x0E, 0)
                .validate(),
            Err(ConfigError::InvalidHeader)
        );
        assert_eq!(
            PacketConfig::new()
                .with_length(PacketLength::Fixed(0))
                .validate(),
            Err(ConfigError::InvalidLength)
        );
    }

    #[test]
    fn airtime() {
        // 16-byte payload at 57.6 kbps: 40 preamble + 16 sync + 8 length + 128 + 16 CRC = 208 bits.
        let m = ModemConfig::new(57_600, 28_800);
        assert_eq!(PacketConfig::new().airtime_us(&m, 16), 3_612);
    }
}
