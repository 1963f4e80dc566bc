//! What OpenLRSng's signal figures mean in the units a link report shows: its RSSI bytes
//! (the chip's 0x26 reading, at the `rssi_off` OpenLRSng programs) in dBm and its 15-slot
//! link quality in percent. Both TauLink ends report an OpenLRSng link with these.

use radio_rfm22b::measure;

/// `rssi_off` of register 0x35, which OpenLRSng programs to 0x2A (see [`crate::modem`]): 2,
/// about 8 dB.
pub const RSSI_OFFSET: u8 = 2;

/// An OpenLRSng RSSI byte (a received packet's, the receiver's smoothed one, or the one a
/// link-info frame carries) in dBm.
pub const fn rssi_dbm(raw: u8) -> i16 {
    measure::rssi_dbm(raw, RSSI_OFFSET)
}

/// A link quality counted in OpenLRSng's 15 slots (`LinkQuality::rx_quality`, a link-info
/// frame's) as a percentage; counts above 15 read 100.
pub const fn quality_percent(quality_of_15: u8) -> u8 {
    let q = if quality_of_15 > 15 {
        15
    } else {
        quality_of_15
    };
    // At most 1500 / 15 = 100: fits in a u8.
    (q as u16 * 100 / 15) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rssi_is_the_chip_reading_less_the_programmed_offset() {
        // 0.5 dB per LSB from −122 dBm, minus 4 dB per `rssi_off` step.
        assert_eq!(rssi_dbm(0), -130);
        assert_eq!(rssi_dbm(100), -80);
        assert_eq!(rssi_dbm(255), -3);
    }

    #[test]
    fn quality_in_percent() {
        assert_eq!(quality_percent(0), 0);
        assert_eq!(quality_percent(12), 80);
        assert_eq!(quality_percent(15), 100);
        assert_eq!(quality_percent(16), 100);
    }
}
