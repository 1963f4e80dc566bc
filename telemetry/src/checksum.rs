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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catalogue_check_value() {
        // The check value of every CRC catalogue entry is the CRC of ASCII "123456789".
        assert_eq!(crc16(b"123456789"), 0x29B1);
    }
}
