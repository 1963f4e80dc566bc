//! Drives one output bank (a timer and its channels) with a `flight_app::outputs::Protocol`.
//! The arithmetic lives in flight-core; this only writes PSC/ARR/CCR and, for OneShot125,
//! fires the one-pulse timer once per control loop.

use embassy_stm32::timer::low_level::{OutputCompareMode, OutputPolarity, Timer};
use embassy_stm32::timer::{Channel, GeneralInstance4Channel};
use flight_app::outputs::{Command, OutputError, Protocol, TimerClock, TimerTiming};

/// A timer bank driving motors or servos.
pub struct MotorTimer<'d, T: GeneralInstance4Channel> {
    timer: Timer<'d, T>,
    channels: &'static [Channel],
    protocol: Protocol,
    timing: TimerTiming,
}

impl<'d, T: GeneralInstance4Channel> MotorTimer<'d, T> {
    /// Sets the timer up for `protocol` with every channel stopped. The pins must already be
    /// in their timer function (board.rs does that, driving them low first).
    pub fn new(
        timer: Timer<'d, T>,
        channels: &'static [Channel],
        protocol: Protocol,
    ) -> Result<Self, OutputError> {
        let max_count = match timer.bits() {
            embassy_stm32::timer::TimerBits::Bits16 => 0xFFFF,
            #[allow(unreachable_patterns)]
            _ => u32::MAX,
        };
        let clock = TimerClock {
            clock_hz: timer.get_clock_frequency().0,
            max_count,
        };
        let timing = protocol.timing(clock)?;
        timer.stop();
        timer.regs_core().psc().write_value(timing.prescaler as u16);
        timer.set_max_compare_value(word::<T>(timing.period));
        timer.set_autoreload_preload(true);
        for &ch in channels {
            timer.set_output_compare_mode(ch, OutputCompareMode::PwmMode1);
            timer.set_output_compare_preload(ch, true);
            // OneShot125: inverted output with CCR = ARR − pulse, so pulses end at ARR.
            timer.set_output_polarity(
                ch,
                if timing.one_pulse {
                    OutputPolarity::ActiveLow
                } else {
                    OutputPolarity::ActiveHigh
                },
            );
            timer.set_compare_value(ch, word::<T>(protocol.compare(&timing, Command::Stopped)));
            timer.enable_channel(ch, true);
        }
        timer
            .regs_core()
            .cr1()
            .modify(|w| w.set_opm(timing.one_pulse));
        timer.enable_outputs();
        timer.generate_update_event();
        if !timing.one_pulse {
            timer.start();
        }
        Ok(Self {
            timer,
            channels,
            protocol,
            timing,
        })
    }

    /// Applies one loop's commands (extra commands are ignored, missing ones stop).
    pub fn apply(&mut self, commands: &[Command]) {
        if self.timing.one_pulse && self.timer.regs_core().cr1().read().cen() {
            // The previous pulse is still running: skip this loop rather than merge pulses.
            return;
        }
        for (i, &ch) in self.channels.iter().enumerate() {
            let command = commands.get(i).copied().unwrap_or(Command::Stopped);
            let compare = self.protocol.compare(&self.timing, command);
            self.timer.set_compare_value(ch, word::<T>(compare));
        }
        if self.timing.one_pulse {
            // Load the preloaded compare values and fire one pulse on every channel at once.
            self.timer.generate_update_event();
            self.timer.start();
        }
    }
}

/// u32 → the timer's word (u16 or u32). Values come from `Protocol::timing`, which already
/// fitted them to the counter width; saturate rather than wrap if that were ever wrong.
fn word<T: GeneralInstance4Channel>(value: u32) -> T::Word {
    T::Word::try_from(value).unwrap_or_else(|_| T::Word::from(u16::MAX))
}
