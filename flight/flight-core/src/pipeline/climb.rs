//! Climb rate from barometric altitude, for the failsafe's rate-controlled descent when no
//! INS runs: a critically damped α-β (g-h) tracker of altitude and climb rate. Differencing
//! the baro would not do: 0.1 m of noise at 50 Hz is 7 m/s of raw derivative, and a first-order
//! low-pass slow enough to hide it (σ ≈ 1 m/s left at τ 0.5 s, measured in tests/flight-sitl)
//! lags a real descent by seconds. The tracker with discount θ = 0.9 per reading
//! (g = 1 − θ², h = (1 − θ)²) leaves σ ≈ 0.085 m/s of the 0.1 m noise on the rate
//! (velocity variance reduction 2h² / (g(4 − 2g − h)) / dt²), follows a steady climb
//! without lag (type 2) and settles in ≈ 10 readings (0.2 s at 50 Hz). The flight loop then
//! blends it with the accelerometer (`FlightLoop::climb_estimate`).

/// Discount factor per reading.
const THETA: f32 = 0.9;
/// Readings further apart than this restart the tracker (a stalled sensor), s.
const MAX_GAP_S: f32 = 0.5;

/// The tracker.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ClimbRate {
    /// Last reading's time, ms, and the altitude estimate then, m.
    last: Option<(u32, f32)>,
    rate_mps: f32,
    readings: u32,
}

/// Readings before the rate is reported: the tracker's settling.
const SETTLE_READINGS: u32 = 10;

impl ClimbRate {
    /// No readings yet.
    pub const fn new() -> Self {
        Self {
            last: None,
            rate_mps: 0.0,
            readings: 0,
        }
    }

    /// The tracked altitude, m (`None` before the first reading): the smoothed baro altitude
    /// the handset shows.
    pub fn altitude_m(&self) -> Option<f32> {
        self.last.map(|(_, altitude)| altitude)
    }

    /// Feeds the altitude (m, up) measured at `now_ms`; returns the climb rate (m/s, up) once
    /// the tracker has settled.
    pub fn update(&mut self, now_ms: u32, altitude_m: f32) -> Option<f32> {
        if !altitude_m.is_finite() {
            return None;
        }
        let Some((t0, estimate)) = self.last else {
            self.last = Some((now_ms, altitude_m));
            return None;
        };
        let dt_s = now_ms.wrapping_sub(t0) as f32 / 1000.0;
        if !(dt_s > 0.0 && dt_s <= MAX_GAP_S) {
            *self = Self::new();
            self.last = Some((now_ms, altitude_m));
            return None;
        }
        let (g, h) = (1.0 - THETA * THETA, (1.0 - THETA) * (1.0 - THETA));
        let predicted = estimate + self.rate_mps * dt_s;
        let residual = altitude_m - predicted;
        self.last = Some((now_ms, predicted + g * residual));
        self.rate_mps += h * residual / dt_s;
        self.readings = self.readings.saturating_add(1);
        (self.readings >= SETTLE_READINGS).then_some(self.rate_mps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follows_a_descent_through_noise() {
        let mut c = ClimbRate::new();
        assert_eq!(c.update(0, 10.0), None);
        // −1 m/s with ±0.1 m alternating noise at 50 Hz, for 3 s: settled within 0.1 m/s.
        let mut rates = Vec::new();
        for k in 1..=150u32 {
            let noise = if k % 2 == 0 { 0.1 } else { -0.1 };
            if let Some(r) = c.update(k * 20, 10.0 - 0.02 * k as f32 + noise) {
                rates.push(r);
            }
        }
        assert_eq!(rates.len(), 150 - 9);
        let tail = &rates[rates.len() - 50..];
        let worst = tail.iter().map(|r| (r + 1.0).abs()).fold(0.0, f32::max);
        assert!(worst < 0.1, "{worst}");
        // A stalled sensor restarts the tracker.
        assert_eq!(c.update(150 * 20 + 2_000, 7.0), None);
        assert_eq!(c.update(150 * 20 + 2_020, 7.0), None);
        assert_eq!(c.update(150 * 20 + 2_040, f32::NAN), None);
    }
}
