//! Flight modes and the switch channel that selects them.

/// What the controller does with the sticks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FlightMode {
    /// Sticks command body rates, PID controller.
    RatePid,
    /// Sticks command body rates, LQG controller.
    RateLqg,
    /// Sticks command roll/pitch angles (self-levelling).
    Attitude,
    /// Attitude near centre, rate at full deflection.
    Horizon,
    /// System identification: the shake excitation on top of rate control.
    SystemId,
    /// Attitude mode with the altitude held (throttle stick centred) or climbing at a rate
    /// (deflected) on the INS vertical (`pipeline::hold`).
    AltitudeHold,
    /// Altitude hold, and the position held while the roll/pitch sticks are centred (GPS).
    PositionHold,
    /// Altitude hold, and the sticks move the held position at a bounded speed (GPS).
    Loiter,
}

impl FlightMode {
    /// Stable number for telemetry.
    pub const fn id(self) -> u8 {
        match self {
            FlightMode::RatePid => 0,
            FlightMode::RateLqg => 1,
            FlightMode::Attitude => 2,
            FlightMode::Horizon => 3,
            FlightMode::SystemId => 4,
            FlightMode::AltitudeHold => 5,
            FlightMode::PositionHold => 6,
            FlightMode::Loiter => 7,
        }
    }

    /// Short name (CRSF FLIGHT_MODE, S.Port, logs).
    pub const fn name(self) -> &'static str {
        match self {
            FlightMode::RatePid => "RATE",
            FlightMode::RateLqg => "LQG",
            FlightMode::Attitude => "ANGL",
            FlightMode::Horizon => "HOR",
            FlightMode::SystemId => "SYSID",
            FlightMode::AltitudeHold => "ALTH",
            FlightMode::PositionHold => "POSH",
            FlightMode::Loiter => "LOIT",
        }
    }

    /// The throttle holds the altitude and the attitude comes from the hold loops.
    pub const fn holds(self) -> bool {
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
