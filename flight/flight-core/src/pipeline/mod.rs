//! The flight loop: one gyro sample in, motor commands out. It composes the pieces the other
//! modules own — attitude estimation, the arming/failsafe supervisor, the flight-mode switch,
//! the LQG and PID controllers and the mixer — in the order the firmware runs them right
//! after each data-ready interrupt, so the outputs are synchronous with the gyro. `setup`
//! derives its configuration from the settings; `channels` turns link channels into sticks;
//! `announce` picks the alerts to sound; `link` keeps the bound link in the settings.

mod announce;
mod attitude;
mod channels;
mod climb;
mod controllers;
mod estimator;
mod failsafe;
mod flight_loop;
pub mod flight_state;
mod guidance;
mod hold;
mod identify;
mod link;
mod setup;
mod stages;
mod sticks;
mod validate;

pub use announce::{BATTERY_REPEAT_MS, announce, announce_battery, battery_alert, loop_alerts};
pub use attitude::Attitude;
pub use channels::{
    ArmChannel, CHANNEL_HIGH, CHANNEL_LOW, CHANNEL_MID, ChannelMap, channel_for, channel_us,
    throttle_channel,
};
pub use climb::ClimbRate;
pub use controllers::{ControlParams, Controllers};
pub use estimator::{
    Estimator, EstimatorMode, INS_START_S, PSEUDO_PERIOD_S, PSEUDO_VAR_M2PS2, Source,
};
pub use failsafe::FAILSAFE_HOLD_MS;
pub use flight_loop::{FlightLoop, ImuSample, LinkInput, LoopConfig, LoopOutput};
pub use hold::{
    DescentHold, Hold, Horizontal, LOITER_SPEED_MPS, MAX_CLIMB_MPS, MAX_SPEED_MPS, MAX_TILT_DEG,
    Nav, STICK_DEADBAND,
};
pub use link::{
    Protocol, bind_band, openlrs_band, protocol, store_link, store_openlrs, stored_link,
    stored_openlrs,
};
pub use setup::{FlightSetup, SetupError, from_settings};
pub use sticks::StickShaping;
pub use validate::{InvalidSettings, validate};
