//! The radio battery on JR pin 3, as the SAADC sees it through the 100 k / 22 k divider
//! (`hardware/taulink-module/README.md`).
//!
//! SAADC single-ended, internal 0.6 V reference, gain 1/6: full scale 3.6 V over 12 bits
//! (nRF52840 PS §6.23.2, RESULT = V · GAIN/REFERENCE · 2^RESOLUTION). The divider scales by
//! 22 / 122, so 8.4 V (2S full) reads 1.515 V at the pin and the ADC covers up to 19.96 V.

/// Full-scale pin voltage, mV: 0.6 V / (1/6).
const FULL_SCALE_MV: u32 = 3_600;
/// 12-bit result range.
const COUNTS: u32 = 4_096;
/// Divider top resistor, kΩ.
const R_TOP_KOHM: u32 = 100;
/// Divider bottom resistor, kΩ.
const R_BOTTOM_KOHM: u32 = 22;

/// Battery voltage in mV from one 12-bit SAADC result (negative noise reads as 0).
pub fn battery_mv(raw: i16) -> u16 {
    let counts = u64::from(u32::try_from(raw).unwrap_or(0).min(COUNTS - 1));
    let numerator = counts * u64::from(FULL_SCALE_MV) * u64::from(R_TOP_KOHM + R_BOTTOM_KOHM);
    let denominator = u64::from(COUNTS) * u64::from(R_BOTTOM_KOHM);
    u16::try_from(numerator / denominator).unwrap_or(u16::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_cell_range_reads_right() {
        // 8.4 V → 1.5148 V at the pin → 1723.5 counts.
        assert_eq!(battery_mv(1723), 8_397);
        assert_eq!(battery_mv(1724), 8_402);
        // 7.4 V nominal → 1518.7 counts.
        assert_eq!(battery_mv(1519), 7_403);
        assert_eq!(battery_mv(0), 0);
        assert_eq!(battery_mv(-5), 0);
        // Clipped to 4095 counts: 3.5991 V at the pin → 19.958 V.
        assert_eq!(battery_mv(i16::MAX), 19_958);
    }
}
