//! The flight loop: one gyro sample in, motor commands out. It composes the pieces the other
//! modules own — attitude estimation, the arming/failsafe supervisor, the flight-mode switch,
//! the LQG and PID controllers and the mixer — in the order the firmware runs them right
//! after each data-ready interrupt, so the outputs are synchronous with the gyro.

mod controllers;
mod flight_loop;
mod sticks;

pub use controllers::{ControlParams, Controllers};
pub use flight_loop::{FlightLoop, ImuSample, LinkInput, LoopConfig, LoopOutput};
pub use sticks::StickShaping;
