//! Climb rate from barometric altitude, for the failsafe's rate-controlled descent when no
//! INS runs: the altitude difference between readings, low-passed. The baro's ≈ 0.1 m noise
//! at 50 Hz would be 5 m/s of raw derivative; a 0.5 s time constant brings it to ≈ 0.2 m/s
//! while a 1 m/s descent still shows within a second.

/// Low-pass time constant, s.
const TAU_S: f32 = 0.5;
/// Readings further apart than this restart the filter (a stalled sensor), s.
const MAX_GAP_S: f32 = 0.5;

/// The filter.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ClimbRate {
    last: Option<(u32, f32)>,
    rate_mps: f32,
}

impl ClimbRate {
    /// No readings yet.
    pub const fn new() -> Self {
        Self {
            last: None,
            rate_mps: 0.0,
        }
    }

    /// Feeds the altitude (m, up) measured at `now_ms`; returns the climb rate (m/s, up) once
    /// two readings are in.
    pub fn update(&mut self, now_ms: u32, altitude_m: f32) -> Option<f32> {
        if !altitude_m.is_finite() {
            return None;
        }
        let previous = self.last.replace((now_ms, altitude_m));
        let (t0, a0) = previous?;
        let dt_s = now_ms.wrapping_sub(t0) as f32 / 1000.0;
        if !(dt_s > 0.0 && dt_s <= MAX_GAP_S) {
            self.rate_mps = 0.0;
            return None;
        }
        let raw = (altitude_m - a0) / dt_s;
        self.rate_mps += dt_s / (TAU_S + dt_s) * (raw - self.rate_mps);
        Some(self.rate_mps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follows_a_descent_and_smooths_noise() {
        let mut c = ClimbRate::new();
        assert_eq!(c.update(0, 10.0), None);
        // −1 m/s with ±0.1 m alternating noise at 50 Hz, for 3 s.
        let mut rate = 0.0;
        for k in 1..=150u32 {
            let noise = if k % 2 == 0 { 0.1 } else { -0.1 };
            rate = c.update(k * 20, 10.0 - 0.02 * k as f32 + noise).unwrap();
        }
        assert!((rate + 1.0).abs() < 0.25, "{rate}");
        // A stalled sensor restarts the estimate.
        assert_eq!(c.update(150 * 20 + 2_000, 7.0), None);
        assert_eq!(c.update(150 * 20 + 2_020, 7.0), Some(0.0));
        assert_eq!(c.update(150 * 20 + 2_040, f32::NAN), None);
    }
}
