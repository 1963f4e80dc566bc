//! `CRC16_add()`: CRC-16/CCITT (poly 0x1021, init 0, MSB first, no final XOR). OpenLRSng uses
//! it for EEPROM blocks and SUMD, not on air (the Si4432 adds its own CRC there).

/// CRC of `data` from the initial value 0.
pub fn crc16(data: &[u8]) -> u16 {
    data.iter().fold(0u16, |crc, &byte| update(crc, byte))
}

/// Feeds one byte, as `CRC16_add` does.
pub fn update(crc: u16, byte: u8) -> u16 {
    let mut crc = crc ^ (u16::from(byte) << 8);
    for _ in 0..8 {
        crc = if crc & 0x8000 != 0 {
            (crc << 1) ^ 0x1021
        } else {
            crc << 1
        };
    }
    crc
}

#[cfg(test)]
mod tests {
    #[test]
    fn check_value() {
        // CRC-16/XMODEM check value over "123456789".
        assert_eq!(super::crc16(b"123456789"), 0x31C3);
    }
}
