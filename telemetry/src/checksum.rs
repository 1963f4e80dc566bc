//! The link's CRC-16, carried on every air packet on top of the chip's own CRC.
//!
//! The Si4432 packet handler checks CRC-16/CCITT (poly 0x1021) over header, length and data.
//! The link CRC deliberately uses a *different* generator, CRC-16/CMS (poly 0x8005, init
//! 0xFFFF): with the same polynomial on nested scopes an error pattern inside the frame
//! passes the outer check exactly when it passes the inner one (E·x^16 ≡ 0 mod g ⇔ E ≡ 0
//! mod g, g coprime to x), so the second CRC would add nothing. With coprime generators a
//! random corruption has to be a multiple of both: about 2^-32 instead of 2^-16. Both
//! generators contain (x + 1), so every odd number of bit errors is caught by each, and
//! both have Hamming distance 4 at our frame lengths (≤ 64 bytes): any 1–3 flipped bits are
//! always detected.
//!
//! [`crc16`] is the chip's check (CCITT), kept for the simulators that model the chip and
//! for anything else that wants CRC-16/CCITT; [`link_crc16`] and [`keyed_crc16`] are the
//! air frames'.

use crc::{CRC_16_CMS, CRC_16_IBM_3740, Crc, NoTable};

/// The link algorithm.
pub const LINK_CRC: Crc<u16> = Crc::<u16>::new(&CRC_16_CMS);
/// The Si4432's CRC-16/CCITT as the packet handler computes it (0x30 crc = 00, init 0xFFFF;
/// IBM-3740 is the catalogue name of CCITT-FALSE). Bit by bit, without the 512-byte table:
/// no image computes it per air frame (the chip does), only over flash pages (the flight
/// log's) and in the simulators.
pub const CHIP_CRC: Crc<u16, NoTable> = Crc::<u16, NoTable>::new(&CRC_16_IBM_3740);

/// Link CRC (CRC-16/CMS) of `bytes`.
pub fn link_crc16(bytes: &[u8]) -> u16 {
    LINK_CRC.checksum(bytes)
}

/// CRC-16/CCITT-FALSE of `bytes`: what the Si4432 packet handler computes.
pub fn crc16(bytes: &[u8]) -> u16 {
    CHIP_CRC.checksum(bytes)
}

/// Link CRC of `key` (4 bytes, little-endian) followed by `bytes`. Air frames key their CRC
/// with the bind ID, so a frame of another link that slipped past the chip's header check
/// (same header bytes by chance, or a chip configured without header checking) still fails
/// here.
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
    fn catalogue_check_values() {
        // The check value of every CRC catalogue entry is the CRC of ASCII "123456789".
        assert_eq!(link_crc16(b"123456789"), 0xAEE7);
        assert_eq!(crc16(b"123456789"), 0x29B1);
    }

    #[test]
    fn keyed_is_crc_of_key_then_bytes() {
        let mut joined = [0u8; 13];
        joined[..4].copy_from_slice(&0x0403_0201u32.to_le_bytes());
        joined[4..].copy_from_slice(b"123456789");
        assert_eq!(keyed_crc16(0x0403_0201, b"123456789"), link_crc16(&joined));
        assert_ne!(keyed_crc16(1, b"abc"), keyed_crc16(2, b"abc"));
    }
}
