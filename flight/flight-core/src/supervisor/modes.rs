//! Flight modes (the type is the wire's, `telemetry::messages::FlightMode`), their flight-only
//! policy, and the switch channel that selects them.

/// What the controller does with the sticks: one type with the link's, defined by the wire
/// crate (its variant index is the stable id the settings store; see its doc).
pub use telemetry::messages::FlightMode;

/// The flight-only policy of a [`FlightMode`] (the wire crate stays free of it).
pub trait ModePolicy {
    /// The throttle holds the altitude and the attitude comes from the hold loops.
    fn holds(self) -> bool;
}

impl ModePolicy for FlightMode {
    fn holds(self) -> bool {
        matches!(
            self,
            FlightMode::AltitudeHold | FlightMode::PositionHold | FlightMode::Loiter
        )
    }
}

/// Maps a switch channel (−1…1) to one of three configured modes, with hysteresis so a
/// switch sitting on a boundary does not flicker.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeSwitch {
    positions: [FlightMode; 3],
    current: usize,
}

impl ModeSwitch {
    /// Low, middle and high switch positions.
    pub const fn new(positions: [FlightMode; 3]) -> Self {
        Self {
            positions,
            current: 0,
        }
    }

    /// Current mode after reading the channel value. Non-finite values keep the mode.
    pub fn update(&mut self, channel: f32) -> FlightMode {
        if channel.is_finite() {
            // Thresholds at ±1/3 with ±0.05 hysteresis around them.
            let band = 0.05;
            let wanted = if channel < -1.0 / 3.0 - band {
                Some(0)
            } else if channel > 1.0 / 3.0 + band {
                Some(2)
            } else if channel.abs() < 1.0 / 3.0 - band {
                Some(1)
            } else {
                None
            };
            if let Some(w) = wanted {
                self.current = w;
            }
        }
        self.mode()
    }

    /// Selects the position that holds `mode` (a resumed flight's), if one does; the next
    /// update from the channel takes over.
    pub fn select(&mut self, mode: FlightMode) {
        if let Some(i) = self.positions.iter().position(|m| *m == mode) {
            self.current = i;
        }
    }

    /// The mode selected now.
    pub fn mode(&self) -> FlightMode {
        self.positions
            .get(self.current)
            .copied()
            .unwrap_or(FlightMode::Attitude)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_positions_with_hysteresis() {
        let mut s = ModeSwitch::new([
            FlightMode::Attitude,
            FlightMode::RatePid,
            FlightMode::RateLqg,
        ]);
        assert_eq!(s.update(-1.0), FlightMode::Attitude);
        assert_eq!(s.update(0.0), FlightMode::RatePid);
        assert_eq!(s.update(1.0), FlightMode::RateLqg);
        // Sitting on the boundary keeps the last clear position.
        assert_eq!(s.update(0.34), FlightMode::RateLqg);
        assert_eq!(s.update(0.2), FlightMode::RatePid);
        assert_eq!(s.update(0.34), FlightMode::RatePid);
        assert_eq!(s.update(f32::NAN), FlightMode::RatePid);
        assert_eq!(FlightMode::SystemId.id(), 4);
    }
}
