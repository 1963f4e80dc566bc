//! The motor timers (outputs 1–4: TIM3 and TIM9), driven by the flight loop itself
//! (`tasks::imu`) right after each step, so the outputs stay synchronous with the gyro; a
//! stalled sensor stops them through the loop's ride-through policy.

use embassy_stm32::peripherals::{TIM3, TIM9};
use embassy_stm32::timer::simple_pwm::PwmPin;
use embassy_stm32::timer::{Ch1, Ch2, Ch3, Ch4};
use flight_app::outputs::Command;

use crate::firmware::outputs::MotorTimer;

/// Both banks of a quad: outputs 1–2 and 3–4.
pub struct Motors {
    /// TIM3 CH3/CH4 (PB0, PB1).
    pub bank0: MotorTimer<'static, TIM3>,
    /// TIM9 CH2/CH1 (PA3, PA2).
    pub bank1: MotorTimer<'static, TIM9>,
    /// The pins, kept in their timer function.
    pub _pins: MotorPins,
}

/// Outputs 1–4 in their timer function (held, never read).
pub type MotorPins = (
    PwmPin<'static, TIM3, Ch3>,
    PwmPin<'static, TIM3, Ch4>,
    PwmPin<'static, TIM9, Ch2>,
    PwmPin<'static, TIM9, Ch1>,
);

impl Motors {
    /// Applies one loop's commands.
    pub fn apply(&mut self, commands: &[Command; 4]) {
        let [m1, m2, m3, m4] = *commands;
        self.bank0.apply(&[m1, m2]);
        self.bank1.apply(&[m3, m4]);
    }
}
