//! Arming, disarming and link failsafe: an explicit state machine that decides whether the
//! motors may turn and who is in command. Pure: it takes the time and the facts each loop
//! and returns a decision; nothing here touches hardware.

mod gesture;
mod landing;
mod machine;
mod modes;

pub use gesture::{Gesture, GestureDetector};
pub use landing::{
    LANDED_CLIMB_MPS, LANDED_HOLD_MS, LandingDetector, LandingInputs, THRUST_MARGIN,
    landed_climb_limit,
};
pub use machine::{
    ArmBlocker, Decision, Inputs, LAST_RESORT_ALTITUDE_M, Settings, State, Supervisor,
    last_resort_ms,
};
pub use modes::{FlightMode, ModePolicy, ModeSwitch};

/// Stick positions as the link delivers them: throttle 0…1, the others −1…1 (centre 0).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sticks {
    /// Throttle, 0 = low.
    pub throttle: f32,
    /// Roll, positive = right.
    pub roll: f32,
    /// Pitch, positive = nose up.
    pub pitch: f32,
    /// Yaw, positive = nose right.
    pub yaw: f32,
}

impl Sticks {
    /// Throttle at the bottom (below 5 %).
    pub fn throttle_low(&self) -> bool {
        self.throttle < 0.05
    }

    /// Roll, pitch and yaw within `deadband` of centre.
    pub fn centred(&self, deadband: f32) -> bool {
        self.roll.abs() <= deadband && self.pitch.abs() <= deadband && self.yaw.abs() <= deadband
    }

    /// All four values are finite numbers.
    pub fn is_finite(&self) -> bool {
        crate::estimation::all_finite(&[self.throttle, self.roll, self.pitch, self.yaw])
    }
}
