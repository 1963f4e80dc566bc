//! MS5611-01BA03 calculations, pure: PROM CRC-4 (AN520), first- and second-order
//! temperature compensation (datasheet "Pressure and temperature calculation" and "Second
//! order temperature compensation"), and the ISA altitude.

/// The eight 16-bit PROM words: word 0 factory data, C1..C6 in words 1..6, CRC in the low
/// nibble of word 7.
pub type Prom = [u16; 8];

/// AN520 CRC-4 over the PROM with the CRC nibble itself zeroed.
#[must_use]
pub fn crc4(prom: &Prom) -> u8 {
    let mut words = *prom;
    if let Some(last) = words.last_mut() {
        *last &= 0xFF00;
    }
    let mut rem: u16 = 0;
    for word in words {
        for byte in word.to_be_bytes() {
            rem ^= u16::from(byte);
            for _ in 0..8 {
                rem = if rem & 0x8000 != 0 {
                    (rem << 1) ^ 0x3000
                } else {
                    rem << 1
                };
            }
        }
    }
    ((rem >> 12) & 0x0F) as u8
}

/// The CRC nibble stored in the PROM.
#[must_use]
pub fn stored_crc(prom: &Prom) -> u8 {
    (prom.last().copied().unwrap_or(0) & 0x0F) as u8
}

/// A compensated reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Reading {
    /// Pressure in 0.01 mbar (Pa).
    pub pressure_pa: i32,
    /// Temperature in 0.01 °C.
    pub temperature_centi_c: i32,
}

/// Compensates raw D1 (pressure) and D2 (temperature) with the calibration words.
#[must_use]
pub fn compensate(prom: &Prom, d1: u32, d2: u32) -> Reading {
    let [_, c1, c2, c3, c4, c5, c6, _] = prom.map(i64::from);
    let (d1, d2) = (i64::from(d1), i64::from(d2));
    // First order.
    let dt = d2 - (c5 << 8);
    let mut temp = 2000 + ((dt * c6) >> 23);
    let mut off = (c2 << 16) + ((c4 * dt) >> 7);
    let mut sens = (c1 << 15) + ((c3 * dt) >> 8);
    // Second order, below 20 °C (and again below −15 °C).
    if temp < 2000 {
        let t2 = (dt * dt) >> 31;
        let low = (temp - 2000) * (temp - 2000);
        let mut off2 = 5 * low / 2;
        let mut sens2 = 5 * low / 4;
        if temp < -1500 {
            let very_low = (temp + 1500) * (temp + 1500);
            off2 += 7 * very_low;
            sens2 += 11 * very_low / 2;
        }
        temp -= t2;
        off -= off2;
        sens -= sens2;
    }
    let p = (((d1 * sens) >> 21) - off) >> 15;
    Reading {
        pressure_pa: i32::try_from(p).unwrap_or(i32::MAX),
        temperature_centi_c: i32::try_from(temp).unwrap_or(i32::MIN),
    }
}

/// Altitude (m) of `pressure_pa` in the ICAO standard atmosphere above the level where the
/// pressure is `sea_level_pa`: h = 44330.77·(1 − (p/p₀)^0.190263), evaluated as
/// −44330.77·expm1(0.190263·ln(p/p₀)) — nothing cancels near p₀, and of libm only `expm1f`
/// (`powf` is 1 KB of flash).
#[must_use]
pub fn altitude_m(pressure_pa: f32, sea_level_pa: f32) -> f32 {
    -44_330.77 * libm::expm1f(0.190_263 * ln(pressure_pa / sea_level_pa))
}

/// ln x: x = 2ᵉ·m with m in [√½, √2), ln m = 2·atanh((m − 1)/(m + 1)) by its series (the
/// argument is below 0.172, six terms reach f32's round-off). 0 gives −∞, ∞ gives ∞,
/// a negative x or NaN gives NaN.
fn ln(x: f32) -> f32 {
    if !(x > 0.0 && x < f32::INFINITY) {
        return if x == 0.0 {
            f32::NEG_INFINITY
        } else if x > 0.0 {
            x
        } else {
            f32::NAN
        };
    }
    // A subnormal x is scaled into the normal range first.
    let (x, scaled) = if x < f32::MIN_POSITIVE {
        (x * 33_554_432.0, 25) // 2²⁵
    } else {
        (x, 0)
    };
    let bits = x.to_bits();
    let mut exponent = ((bits >> 23) & 0xFF) as i32 - 127 - scaled;
    let mut m = f32::from_bits((bits & 0x007F_FFFF) | 0x3F80_0000);
    if m > core::f32::consts::SQRT_2 {
        m *= 0.5;
        exponent += 1;
    }
    let u = (m - 1.0) / (m + 1.0);
    let s = u * u;
    let series =
        1.0 + s * (1.0 / 3.0 + s * (1.0 / 5.0 + s * (1.0 / 7.0 + s * (1.0 / 9.0 + s / 11.0))));
    exponent as f32 * core::f32::consts::LN_2 + 2.0 * u * series
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The datasheet's worked example (MS5611-01BA03 p. 8).
    const EXAMPLE: Prom = [0, 40127, 36924, 23317, 23282, 33464, 28312, 0];

    #[test]
    fn datasheet_example() {
        let r = compensate(&EXAMPLE, 9_085_466, 8_569_150);
        assert_eq!(r.temperature_centi_c, 2007);
        assert_eq!(r.pressure_pa, 100_009);
    }

    #[test]
    fn second_order_lowers_cold_readings() {
        // D2 chosen for about −20 °C: the second-order terms apply (both branches).
        let d2 = 8_569_150 - 1_300_000;
        let first_temp = 2000 + (((i64::from(d2) - (33464 << 8)) * 28312) >> 23);
        assert!(first_temp < -1500, "{first_temp}");
        let r = compensate(&EXAMPLE, 9_085_466, d2);
        // T2 = dT²/2³¹ is subtracted
        let dt = i64::from(d2) - (33464 << 8);
        assert_eq!(
            i64::from(r.temperature_centi_c),
            first_temp - ((dt * dt) >> 31)
        );
    }

    #[test]
    fn crc4_matches_a_valid_prom_and_catches_a_flip() {
        // A PROM whose CRC nibble is set to the computed value verifies; one flipped bit
        // in a coefficient does not.
        let mut prom = EXAMPLE;
        prom[7] = 0x4500;
        prom[7] |= u16::from(crc4(&prom));
        assert_eq!(crc4(&prom), stored_crc(&prom));
        let mut bad = prom;
        bad[3] ^= 0x0100;
        assert_ne!(crc4(&bad), stored_crc(&bad));
    }

    #[test]
    fn crc4_known_value() {
        // AN520's algorithm on all-zero words gives 0; a single 0x01 high byte in word 0
        // gives the polynomial's remainder, computed by hand: 0x0B.
        assert_eq!(crc4(&[0; 8]), 0);
        let mut prom = [0; 8];
        prom[0] = 0x0100;
        let by_hand = {
            let mut rem: u16 = 1;
            for _ in 0..8 * 16 - 8 + 8 {
                rem = if rem & 0x8000 != 0 {
                    (rem << 1) ^ 0x3000
                } else {
                    rem << 1
                };
            }
            ((rem >> 12) & 0xF) as u8
        };
        assert_eq!(crc4(&prom), by_hand);
    }

    #[test]
    fn ln_agrees_with_std() {
        let mut worst = 0.0f64;
        let mut x = 1e-44f32;
        while x < 3e38 {
            for v in [x, x * 1.01, x * 1.414, x * 1.42, x * 1.9] {
                let want = f64::from(v).ln();
                let error = (f64::from(ln(v)) - want).abs() / want.abs().max(1.0);
                worst = worst.max(error);
            }
            x *= 1.37;
        }
        assert!(worst < 2.5e-7, "{worst}");
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(ln(0.0), f32::NEG_INFINITY);
        assert_eq!(ln(f32::INFINITY), f32::INFINITY);
        assert!(ln(-1.0).is_nan() && ln(f32::NAN).is_nan());
    }

    #[test]
    fn altitude_within_two_millimetres_of_the_f64_formula() {
        // From 30 kPa (≈ 9 km) to 110 kPa, against sea-level pressures of a real day: at
        // most 1.5 mm off (f32's step at 9 km is 1 mm; `powf` in f32 was 3.0 mm off).
        for sea in [98_000.0f32, 101_325.0, 103_500.0] {
            let mut p = 30_000.0f32;
            while p < 110_000.0 {
                let want = 44_330.77 * (1.0 - (f64::from(p) / f64::from(sea)).powf(0.190_263));
                let got = f64::from(altitude_m(p, sea));
                assert!((got - want).abs() < 2e-3, "{p} {sea}: {got} vs {want}");
                p += 37.3;
            }
        }
    }

    #[test]
    fn altitude_of_standard_pressures() {
        assert!(altitude_m(101_325.0, 101_325.0).abs() < 1e-3);
        // ISA: 89 874.6 Pa at 1000 m
        assert!((altitude_m(89_874.6, 101_325.0) - 1000.0).abs() < 1.0);
    }
}
