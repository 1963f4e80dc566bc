//! Conversions of the chip's measurements: RSSI (0x26) to dBm, the AFC correction (0x2B/0x2C)
//! to Hz, and the temperature ADC (0x11) to °C. Pure.

/// dBm from a raw RSSI byte: about 0.5 dB per LSB, −122 dBm at 0 (Tau Labs' calibration:
/// 45 → −100 dBm, 205 → −20 dBm), minus ≈ 4 dB per step of the 0x35 `rssi_off` setting.
pub const fn rssi_dbm(raw: u8, rssi_offset: u8) -> i16 {
    (raw >> 1) as i16 - 122 - 4 * (rssi_offset & 7) as i16
}

/// The raw RSSI byte for a threshold in dBm (for 0x27, the clear-channel threshold).
pub const fn rssi_raw(dbm: i16) -> u8 {
    let raw = (dbm + 122) * 2;
    if raw < 0 {
        0
    } else if raw > 255 {
        255
    } else {
        raw as u8
    }
}

/// The AFC correction in Hz from 0x2B (`afc_corr[9:2]`) and 0x2C (bits 7:6 = `afc_corr[1:0]`):
/// a signed 10-bit value in steps of 156.25 Hz · (hbsel+1). (Tau Labs reads it unsigned and
/// with a zero step in the 433 band; both are bugs.)
pub const fn afc_offset_hz(reg_2b: u8, reg_2c: u8, high_band: bool) -> i32 {
    let raw = ((reg_2b as u16) << 2) | (reg_2c >> 6) as u16;
    // Sign-extend 10 bits.
    let value = ((raw << 6) as i16 >> 6) as i32;
    let step_millihertz = if high_band { 312_500 } else { 156_250 };
    value * step_millihertz / 1_000
}

/// Temperature in tenths of °C from the ADC value, for the driver's sensor setup
/// (0x12 = 0x20: range −64…+64 °C at 0.5 °C per LSB, datasheet, "Temperature Sensor").
pub const fn temperature_decidegrees_c(adc: u8) -> i16 {
    adc as i16 * 5 - 640
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rssi() {
        assert_eq!(rssi_dbm(45, 0), -100);
        assert_eq!(rssi_dbm(205, 0), -20);
        assert_eq!(rssi_dbm(0, 0), -122);
        assert_eq!(rssi_dbm(255, 0), 5);
        assert_eq!(rssi_dbm(45, 2), -108);
        // Tau Labs' CCA threshold 0x27 = 0x40 is −90 dBm.
        assert_eq!(rssi_raw(-90), 0x40);
        assert_eq!(rssi_raw(-200), 0);
        assert_eq!(rssi_raw(10), 255);
    }

    #[test]
    fn afc() {
        assert_eq!(afc_offset_hz(0x00, 0x40, false), 156);
        assert_eq!(afc_offset_hz(0x01, 0x00, false), 625);
        assert_eq!(afc_offset_hz(0xFF, 0xC0, false), -156);
        assert_eq!(afc_offset_hz(0x80, 0x00, false), -80_000);
        assert_eq!(afc_offset_hz(0x7F, 0xC0, true), 159_687);
        assert_eq!(afc_offset_hz(0xFF, 0xC0, true), -312);
    }

    #[test]
    fn temperature() {
        assert_eq!(temperature_decidegrees_c(0), -640);
        assert_eq!(temperature_decidegrees_c(128), 0);
        assert_eq!(temperature_decidegrees_c(178), 250);
    }
}
