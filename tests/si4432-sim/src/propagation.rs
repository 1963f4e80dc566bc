//! Link budget: free-space path loss, receiver noise and sensitivity, bit error rate.
//!
//! Numbers: Si4432 sensitivity is about −121 dBm at 2.4 kbit/s and rises 10·log10 per
//! bit-rate decade (≈ −104 dBm at 128 kbit/s, datasheet Table 3). The BER curve is
//! non-coherent FSK, BER = ½·exp(−γ/2), scaled so that BER = 10⁻³ exactly at sensitivity.

/// Speed of light in m/s.
const SPEED_OF_LIGHT_M_S: f64 = 299_792_458.0;

/// SNR (linear) at which non-coherent FSK reaches BER 10⁻³: γ = 2·ln(500).
const GAMMA_AT_SENSITIVITY: f64 = 12.429_216_196_844_383;

/// Path loss in dB between isotropic antennas `distance_m` apart at `frequency_hz`,
/// with path-loss `exponent` (2 = free space): FSPL = 20·log10(4π·d0/λ) + 10·n·log10(d/d0),
/// d0 = 1 m. Distances under 1 m count as 1 m.
pub fn path_loss_db(distance_m: f64, frequency_hz: f64, exponent: f64) -> f64 {
    let wavelength_m = SPEED_OF_LIGHT_M_S / frequency_hz;
    let at_one_metre = 20.0 * (4.0 * std::f64::consts::PI / wavelength_m).log10();
    at_one_metre + 10.0 * exponent * distance_m.max(1.0).log10()
}

/// Receiver sensitivity (BER 10⁻³) at `bit_rate_bps`, in dBm.
pub fn sensitivity_dbm(bit_rate_bps: f64) -> f64 {
    -121.0 + 10.0 * (bit_rate_bps.max(1.0) / 2_400.0).log10()
}

/// Equivalent in-band noise power for `bit_rate_bps` in dBm: sensitivity minus the SNR the
/// demodulator needs there (10.9 dB).
pub fn noise_floor_dbm(bit_rate_bps: f64) -> f64 {
    sensitivity_dbm(bit_rate_bps) - 10.0 * GAMMA_AT_SENSITIVITY.log10()
}

/// Bit error probability for a signal of `signal_dbm` against `noise_and_interference_dbm`.
pub fn bit_error_rate(signal_dbm: f64, noise_and_interference_dbm: f64) -> f64 {
    let gamma = dbm_to_mw(signal_dbm - noise_and_interference_dbm);
    (0.5 * (-gamma / 2.0).exp()).min(0.5)
}

/// dBm (or dB) to milliwatts (or a linear ratio).
pub fn dbm_to_mw(dbm: f64) -> f64 {
    10f64.powf(dbm / 10.0)
}

/// Milliwatts to dBm; zero power maps to −200 dBm.
pub fn mw_to_dbm(mw: f64) -> f64 {
    if mw <= 0.0 { -200.0 } else { 10.0 * mw.log10() }
}

/// The RSSI register value for an in-band power: raw = 2·(dBm + 122) + 8·rssi_off, clamped
/// to 0..=255 (Tau Labs' dBm = raw/2 − 122 at rssi_off 0).
pub fn rssi_register(power_dbm: f64, rssi_offset: u8) -> u8 {
    let raw = 2.0 * (power_dbm + 122.0) + 8.0 * f64::from(rssi_offset);
    raw.round().clamp(0.0, 255.0) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_space_loss_at_433_mhz() {
        // FSPL(1 km, 433 MHz) = 20·log10(1000) + 20·log10(433e6) − 147.55 = 85.18 dB.
        let loss = path_loss_db(1000.0, 433e6, 2.0);
        assert!((loss - 85.18).abs() < 0.02, "{loss}");
        // Doubling the distance adds 6.02 dB in free space.
        let d = path_loss_db(2000.0, 433e6, 2.0) - loss;
        assert!((d - 6.02).abs() < 0.01, "{d}");
    }

    #[test]
    fn sensitivity_and_ber_waterfall() {
        assert!((sensitivity_dbm(2_400.0) + 121.0).abs() < 1e-9);
        assert!((sensitivity_dbm(128_000.0) + 103.73).abs() < 0.01);
        let noise = noise_floor_dbm(57_600.0);
        let s = sensitivity_dbm(57_600.0);
        assert!((bit_error_rate(s, noise) - 1e-3).abs() < 1e-9);
        assert!(bit_error_rate(s + 3.0, noise) < 3e-6);
        assert!(bit_error_rate(s - 3.0, noise) > 0.02);
    }

    #[test]
    fn rssi_register_matches_tau_labs_examples() {
        // Tau Labs: raw 45 → −100 dBm (45>>1 = 22 → −100), raw 205 → −20 dBm.
        assert_eq!(rssi_register(-99.5, 0), 45);
        assert_eq!(rssi_register(-19.5, 0), 205);
        assert_eq!(rssi_register(-100.0, 2), 60);
        assert_eq!(rssi_register(0.0, 7), 255);
        assert_eq!(rssi_register(-140.0, 0), 0);
    }
}
