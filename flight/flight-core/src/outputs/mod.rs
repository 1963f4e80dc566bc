//! Motor and servo outputs: the protocols (brushed PWM, standard PWM, OneShot125), the timer
//! arithmetic behind them, and which outputs share a timer. Pure: the firmware writes the
//! numbers computed here into PSC/ARR/CCR.

mod bank;
mod protocol;

pub use bank::{BANKS, Bank, BankError, check_assignment};
pub use protocol::{Command, OutputError, Protocol, TimerClock, TimerTiming};
