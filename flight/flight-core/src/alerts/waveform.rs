//! The DAC side of the tones: a sine table played by DMA and the TIM6 period that sets the
//! pitch (Tau Labs' scheme: 130 samples per cycle, 0.4 Vpp centred on 0.5 V, which a VTX's
//! line-level audio input takes without clipping).

/// Samples per sine cycle.
pub const DAC_SAMPLES_PER_CYCLE: usize = 130;

/// Fills `table` with one sine cycle for the 12-bit DAC: `centre_mv` ± `amplitude_mv`
/// (peak) at a 3.3 V reference. Run once at boot.
pub fn sine_table(table: &mut [u16], centre_mv: f32, amplitude_mv: f32) {
    let n = table.len().max(1) as f32;
    let counts_per_mv = 4095.0 / 3300.0;
    for (i, sample) in table.iter_mut().enumerate() {
        let phase = 2.0 * core::f32::consts::PI * i as f32 / n;
        let (sin, _) = crate::estimation::math::sin_cos(phase);
        let mv = centre_mv + amplitude_mv * sin;
        *sample = (mv * counts_per_mv + 0.5).clamp(0.0, 4095.0) as u16;
    }
}

/// TIM6 auto-reload for `frequency_hz` with a table of `samples` per cycle, on the 84 MHz
/// APB1 timer clock (prescaler 0): one DAC update per timer period.
pub fn dac_sample_period_ticks(frequency_hz: u16, samples: usize) -> Option<u32> {
    let per_second = u32::from(frequency_hz).checked_mul(u32::try_from(samples).ok()?)?;
    if per_second == 0 {
        return None;
    }
    let ticks = (84_000_000 + per_second / 2) / per_second;
    (ticks >= 2).then_some(ticks - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tau_labs_table_levels() {
        let mut t = [0u16; DAC_SAMPLES_PER_CYCLE];
        sine_table(&mut t, 500.0, 200.0);
        let max = *t.iter().max().unwrap();
        let min = *t.iter().min().unwrap();
        // 700 mV = 869 counts, 300 mV = 372 counts.
        assert!((868..=869).contains(&max), "{max}");
        assert!((372..=373).contains(&min), "{min}");
        assert_eq!(
            t[0], 620,
            "starts at the centre: 500 mV × 4095 / 3300 = 620.5"
        );
    }

    #[test]
    fn timer_periods_for_tau_labs_pitches() {
        // 84 MHz / (1420 × 130) = 455.0 → ARR 454; 5680 Hz → 113.8 → 114 → ARR 113.
        assert_eq!(dac_sample_period_ticks(1420, 130), Some(454));
        assert_eq!(dac_sample_period_ticks(5680, 130), Some(113));
        assert_eq!(dac_sample_period_ticks(0, 130), None);
    }
}
