//! The link's CRC-16, carried on every air packet on top of the chip's own CRC.
//!
//! CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF): the same check the Si4432's packet handler
//! offers as "CCITT", so a packet is protected by two independent implementations.

use crc::{CRC_16_IBM_3740, Crc};

/// The algorithm (CRC-16/IBM-3740 is the catalogue name of CCITT-FALSE).
pub const LINK_CRC: Crc<u16> = Crc::<u16>::new(&CRC_16_IBM_3740);

/// CRC of `bytes`.
pub fn crc16(bytes: &[u8]) -> u16 {
    LINK_CRC.checksum(bytes)
}

/// CRC of `key` (4 bytes, little-endian) followed by `bytes`. Air frames key their CRC with
/// the bind ID, so a frame of another link that slipped past the chip's header check (same
/// header bytes by chance, or a chip configured without header checking) still fails here.
pub fn keyed_crc16(key: u32, bytes: &[u8]) -> u16 {
    let mut digest = LINK_CRC.digest();
    digest.update(&key.to_le_bytes());
    digest.update(bytes);
    digest.finalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catalogue_check_value() {
        // The check value of every CRC catalogue entry is the CRC of ASCII "123456789".
        assert_eq!(crc16(b"123456789"), 0x29B1);
    }

    #[test]
    fn keyed_is_crc_of_key_then_bytes() {
        let mut joined = [0u8; 13];
        joined[..4].copy_from_slice(&0x0403_0201u32.to_le_bytes());
        joined[4..].copy_from_slice(b"123456789");
        assert_eq!(keyed_crc16(0x0403_0201, b"123456789"), crc16(&joined));
        assert_ne!(keyed_crc16(1, b"abc"), keyed_crc16(2, b"abc"));
    }
}
