//! One output protocol on one timer: prescaler and period for the bank, compare value per
//! command.
//!
//! OneShot125 follows dRonin's one-pulse scheme rather than Tau Labs' free-running timer:
//! the period is 1.02 × the longest pulse plus 10 µs of dead time, the output is inverted and
//! the compare value is `ARR − pulse`, so every pulse ends exactly at the update event and
//! the timer stops by itself. A trigger that arrives while a pulse is still running is
//! ignored by the timer, so pulses can never merge (Tau Labs' 16-bit timers fired a second
//! pulse when no gyro sample came within 5.46 ms).

/// A timer's input clock and counter width.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TimerClock {
    /// Counter clock before the prescaler (84 MHz on APB1 timers, 168 MHz on APB2 ones).
    pub clock_hz: u32,
    /// Largest value the counter and ARR hold (0xFFFF, or 0xFFFF_FFFF for TIM2/TIM5).
    pub max_count: u32,
}

/// How an output bank drives its pins.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Protocol {
    /// Brushed motors through low-side FETs: duty cycle = command, above audible range.
    Brushed {
        /// PWM frequency, 1–64 kHz (16–32 kHz is inaudible).
        frequency_hz: u32,
    },
    /// Servo-style PWM for ESCs and servos.
    Pwm {
        /// Frame rate, 50–490 Hz.
        rate_hz: u32,
        /// Pulse for command 0 (and for "stopped"), µs.
        min_us: u16,
        /// Pulse for command 1, µs.
        max_us: u16,
    },
    /// OneShot125: 125–250 µs pulses, one per control loop, triggered by the loop.
    OneShot125,
}

/// What an output is asked to do.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Motor stopped (disarmed, failsafe-disarmed, power-on): 0 % duty or the min pulse.
    Stopped,
    /// Throttle 0…1; values outside are clamped, non-finite ones mean `Stopped`.
    Throttle(f32),
}

/// Timer settings for one bank.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TimerTiming {
    /// PSC register: the counter runs at clock / (prescaler + 1).
    pub prescaler: u32,
    /// ARR register: the period is `period + 1` counter ticks.
    pub period: u32,
    /// Counter ticks per microsecond × 1000 (kept as an integer for exact µs conversions).
    pub ticks_per_ms: u32,
    /// One-pulse mode with inverted output (OneShot125).
    pub one_pulse: bool,
}

/// Why a protocol cannot run on a timer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OutputError {
    /// Frequency or rate outside what the protocol allows.
    RateOutOfRange,
    /// Pulse limits outside 500–2500 µs or min ≥ max.
    BadPulseLimits,
    /// The timer cannot produce the period with any prescaler.
    TimerCannotFit,
}

impl core::fmt::Display for OutputError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            OutputError::RateOutOfRange => "output rate out of range",
            OutputError::BadPulseLimits => "pulse limits out of range",
            OutputError::TimerCannotFit => "the timer cannot produce this period",
        })
    }
}

impl core::error::Error for OutputError {}

/// OneShot125 pulse limits.
const ONESHOT_MIN_NS: u32 = 125_000;
const ONESHOT_MAX_NS: u32 = 250_000;
/// dRonin: period = 1.02 × longest pulse + 10 µs dead time.
const ONESHOT_PERIOD_NS: u32 = ONESHOT_MAX_NS / 50 * 51 + 10_000;

impl Protocol {
    /// Prescaler and period for this protocol on `timer`, with the finest resolution that
    /// fits (the smallest prescaler), except for PWM which runs at 1 MHz so that the compare
    /// value is the pulse in µs, as every ESC setup expects.
    pub fn timing(&self, timer: TimerClock) -> Result<TimerTiming, OutputError> {
        let (period_ns, one_pulse) = match *self {
            Protocol::Brushed { frequency_hz } => {
                if !(1_000..=64_000).contains(&frequency_hz) {
                    return Err(OutputError::RateOutOfRange);
                }
                (1_000_000_000 / u64::from(frequency_hz), false)
            }
            Protocol::Pwm {
                rate_hz,
                min_us,
                max_us,
            } => {
                if !(50..=490).contains(&rate_hz) {
                    return Err(OutputError::RateOutOfRange);
                }
                if min_us < 500 || max_us > 2500 || min_us >= max_us {
                    return Err(OutputError::BadPulseLimits);
                }
                let prescaler = (timer.clock_hz / 1_000_000).saturating_sub(1);
                if !timer.clock_hz.is_multiple_of(1_000_000) {
                    return Err(OutputError::TimerCannotFit);
                }
                let period = 1_000_000 / rate_hz - 1;
                if period > timer.max_count {
                    return Err(OutputError::TimerCannotFit);
                }
                return Ok(TimerTiming {
                    prescaler,
                    period,
                    ticks_per_ms: 1_000,
                    one_pulse: false,
                });
            }
            Protocol::OneShot125 => (u64::from(ONESHOT_PERIOD_NS), true),
        };
        let clock = u64::from(timer.clock_hz);
        let ticks = clock * period_ns / 1_000_000_000;
        // Smallest divider that brings the period under the counter's range.
        let divider = ticks / (u64::from(timer.max_count) + 1) + 1;
        let period = ticks / divider;
        if period < 2 || divider > 0x1_0000 {
            return Err(OutputError::TimerCannotFit);
        }
        Ok(TimerTiming {
            prescaler: (divider - 1) as u32,
            period: (period - 1) as u32,
            ticks_per_ms: (clock / divider / 1_000) as u32,
            one_pulse,
        })
    }

    /// Compare value (CCR) for `command` on a bank set up with `timing`.
    pub fn compare(&self, timing: &TimerTiming, command: Command) -> u32 {
        let throttle = match command {
            Command::Throttle(t) if t.is_finite() => Some(t.clamp(0.0, 1.0)),
            _ => None,
        };
        let ticks_for_ns =
            |ns: u32| (u64::from(ns) * u64::from(timing.ticks_per_ms) / 1_000_000) as u32;
        match *self {
            Protocol::Brushed { .. } => match throttle {
                // Duty = throttle of the full period (ARR + 1 ticks); 0 is truly off.
                Some(t) => ((timing.period + 1) as f32 * t + 0.5) as u32,
                None => 0,
            },
            Protocol::Pwm { min_us, max_us, .. } => {
                let span = f32::from(max_us - min_us);
                let us = match throttle {
                    Some(t) => f32::from(min_us) + span * t,
                    None => f32::from(min_us),
                };
                (us + 0.5) as u32
            }
            Protocol::OneShot125 => {
                let span = (ONESHOT_MAX_NS - ONESHOT_MIN_NS) as f32;
                let pulse_ns = match throttle {
                    Some(t) => ONESHOT_MIN_NS + (span * t + 0.5) as u32,
                    None => ONESHOT_MIN_NS,
                };
                // Inverted output: low until CCR, high from CCR to ARR, so the pulse ends at
                // the update event.
                timing.period.saturating_sub(ticks_for_ns(pulse_ns))
            }
        }
    }

    /// The highest loop rate at which every loop gets its own pulse. Above it, triggers that
    /// arrive during a pulse are dropped by the one-pulse timer (never merged), and
    /// free-running protocols simply show the latest value at their own rate.
    pub fn max_synchronous_rate_hz(&self) -> u32 {
        match *self {
            Protocol::OneShot125 => 1_000_000_000 / ONESHOT_PERIOD_NS,
            Protocol::Brushed { frequency_hz } => frequency_hz,
            Protocol::Pwm { rate_hz, .. } => rate_hz,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const APB1: TimerClock = TimerClock {
        clock_hz: 84_000_000,
        max_count: 0xFFFF,
    };
    const APB2: TimerClock = TimerClock {
        clock_hz: 168_000_000,
        max_count: 0xFFFF,
    };

    #[test]
    fn brushed_32khz_on_both_timer_clocks() {
        let p = Protocol::Brushed {
            frequency_hz: 32_000,
        };
        let t3 = p.timing(APB1).unwrap();
        assert_eq!((t3.prescaler, t3.period), (0, 2624)); // 84 MHz / 32 kHz = 2625 ticks
        let t9 = p.timing(APB2).unwrap();
        assert_eq!((t9.prescaler, t9.period), (0, 5249));
        assert_eq!(p.compare(&t3, Command::Throttle(0.5)), 1313);
        assert_eq!(p.compare(&t3, Command::Throttle(1.0)), 2625, "100 % duty");
        assert_eq!(p.compare(&t3, Command::Stopped), 0);
        assert_eq!(
            p.compare(&t3, Command::Throttle(f32::NAN)),
            0,
            "NaN stops the motor"
        );
        assert_eq!(p.compare(&t3, Command::Throttle(-3.0)), 0);
    }

    #[test]
    fn pwm_runs_at_one_mhz_so_compare_is_microseconds() {
        let p = Protocol::Pwm {
            rate_hz: 400,
            min_us: 1000,
            max_us: 2000,
        };
        let t = p.timing(APB2).unwrap();
        assert_eq!((t.prescaler, t.period), (167, 2499));
        assert_eq!(p.compare(&t, Command::Stopped), 1000);
        assert_eq!(p.compare(&t, Command::Throttle(0.25)), 1250);
        assert_eq!(p.compare(&t, Command::Throttle(2.0)), 2000);
        let slow = Protocol::Pwm {
            rate_hz: 50,
            min_us: 1000,
            max_us: 2000,
        };
        assert_eq!(slow.timing(APB1).unwrap().period, 19_999);
        assert_eq!(
            Protocol::Pwm {
                rate_hz: 1000,
                min_us: 1000,
                max_us: 2000
            }
            .timing(APB1),
            Err(OutputError::RateOutOfRange)
        );
    }

    #[test]
    fn oneshot_pulses_end_at_the_update_event() {
        let p = Protocol::OneShot125;
        let t = p.timing(APB2).unwrap();
        // 265 µs at 168 MHz = 44 520 ticks: fits 16 bits without a prescaler.
        assert_eq!((t.prescaler, t.period), (0, 44_519));
        assert!(t.one_pulse);
        // Stopped = 125 µs = 21 000 ticks before ARR; full = 250 µs = 42 000 ticks.
        assert_eq!(p.compare(&t, Command::Stopped), 44_519 - 21_000);
        assert_eq!(p.compare(&t, Command::Throttle(1.0)), 44_519 - 42_000);
        assert_eq!(p.compare(&t, Command::Throttle(0.5)), 44_519 - 31_500);
        assert_eq!(p.max_synchronous_rate_hz(), 3773);
    }

    #[test]
    fn slow_rates_on_16_bit_timers_get_a_prescaler() {
        let p = Protocol::Brushed {
            frequency_hz: 1_000,
        };
        let t = p.timing(APB2).unwrap();
        // 168 000 ticks do not fit 16 bits: divide by 3 → 56 000.
        assert_eq!((t.prescaler, t.period), (2, 55_999));
        let wide = TimerClock {
            clock_hz: 84_000_000,
            max_count: u32::MAX,
        };
        assert_eq!(p.timing(wide).unwrap().prescaler, 0, "TIM5 is 32-bit");
    }
}
