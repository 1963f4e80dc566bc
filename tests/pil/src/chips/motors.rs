//! A motor output pin read back: its edges give the pulse width and period, and the output
//! protocol's mapping (`flight_app::outputs::Protocol`, the one the settings choose and
//! flight-sitl flies) turns them into the command an ESC or a brushed FET makes of them:
//! brushed — the duty cycle; PWM — (pulse − min) / (max − min); OneShot125 — (pulse −
//! 125 µs) / 125 µs. A pin that stops pulsing is a stopped motor (an ESC without pulses
//! stops; a FET held low is off, held high full on).

use flight_app::outputs::{Command, Protocol};

/// Below this command the motor counts as stopped (half a step of the finest output: an
/// 84 MHz timer's brushed duty at 32 kHz has 2 625 steps).
const STOPPED_BELOW: f32 = 1e-4;

/// One output pin's recent pulses.
#[derive(Debug, Clone, Default)]
pub struct PulseMeter {
    level: bool,
    changed_ns: u64,
    /// The last rising edge, ns.
    rise_ns: Option<u64>,
    /// The last complete pulse: (rising edge ns, high ns, period ns to the previous rise).
    last: Option<(u64, u64, Option<u64>)>,
    /// Every rising edge (pulse start) since the last [`PulseMeter::take_starts`].
    starts: Vec<u64>,
    /// From the rise before the last one to the last one, ns.
    pending_period: Option<u64>,
    /// Every complete pulse (start ns, width ns) since the last [`PulseMeter::take_pulses`].
    pulses: Vec<(u64, u64)>,
}

impl PulseMeter {
    /// A pin held low.
    pub fn new() -> Self {
        Self::default()
    }

    /// The pin changes to `high` at `t_ns`.
    pub fn edge(&mut self, t_ns: u64, high: bool) {
        if high == self.level {
            return;
        }
        if high {
            let period = self.rise_ns.map(|r| t_ns.saturating_sub(r));
            self.rise_ns = Some(t_ns);
            self.starts.push(t_ns);
            // The period ending at this rise belongs to the pulse that started it.
            self.pending_period = period;
        } else if let Some(r) = self.rise_ns {
            let width = t_ns.saturating_sub(r);
            self.last = Some((r, width, self.pending_period));
            self.pulses.push((r, width));
        }
        self.level = high;
        self.changed_ns = t_ns;
    }

    /// The board lost power at `t_ns`: the pin falls and the motor (a FET gate or an
    /// ESC input with its pull-down) has no pulse to go on — stopped at once, not after
    /// the quiet periods that tell a stopped output from a slow one.
    pub fn power_lost(&mut self, t_ns: u64) {
        self.edge(t_ns, false);
        self.last = None;
    }

    /// The level now.
    pub fn level(&self) -> bool {
        self.level
    }

    /// Pulse starts (rising edges) since the last call.
    pub fn take_starts(&mut self) -> Vec<u64> {
        std::mem::take(&mut self.starts)
    }

    /// Complete pulses (start ns, width ns) since the last call.
    pub fn take_pulses(&mut self) -> Vec<(u64, u64)> {
        std::mem::take(&mut self.pulses)
    }

    /// The last complete pulse's width and the period before it, ns.
    pub fn last_pulse(&self) -> Option<(u64, Option<u64>)> {
        self.last.map(|(_, h, p)| (h, p))
    }

    /// What a motor makes of this pin at `now_ns` under `protocol`.
    pub fn command(&self, protocol: &Protocol, now_ns: u64) -> Command {
        let quiet_ns = now_ns.saturating_sub(self.changed_ns);
        match *protocol {
            Protocol::Brushed { frequency_hz } => {
                let period_ns = 1_000_000_000 / u64::from(frequency_hz.max(1));
                // Held at one level for two periods: 0 % or 100 %.
                if quiet_ns > 2 * period_ns || self.last.is_none() {
                    return if self.level {
                        Command::Throttle(1.0)
                    } else {
                        Command::Stopped
                    };
                }
                let (high, period) = self.last_pulse().unwrap_or((0, None));
                let period = period.unwrap_or(period_ns).max(1);
                throttle(high as f32 / period as f32)
            }
            Protocol::Pwm {
                rate_hz,
                min_us,
                max_us,
            } => {
                let frame_ns = 1_000_000_000 / u64::from(rate_hz.max(1));
                if quiet_ns > 3 * frame_ns {
                    return Command::Stopped;
                }
                let high_us = self.last_pulse().map_or(0.0, |(h, _)| h as f32 / 1e3);
                let span = f32::from(max_us.saturating_sub(min_us)).max(1.0);
                throttle((high_us - f32::from(min_us)) / span)
            }
            Protocol::OneShot125 => {
                // An ESC stops without a pulse for a few loop periods.
                if quiet_ns > 5_000_000 && !self.level {
                    return Command::Stopped;
                }
                let high_us = self.last_pulse().map_or(0.0, |(h, _)| h as f32 / 1e3);
                throttle((high_us - 125.0) / 125.0)
            }
        }
    }
}

fn throttle(x: f32) -> Command {
    let x = x.clamp(0.0, 1.0);
    if x < STOPPED_BELOW {
        Command::Stopped
    } else {
        Command::Throttle(x)
    }
}

/// The thrust command quad-sim takes for `c` (stopped = 0).
pub fn to_quad(c: Command) -> f32 {
    match c {
        Command::Throttle(x) => x,
        Command::Stopped => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pulses(m: &mut PulseMeter, from: u64, high: u64, period: u64, n: u64) -> u64 {
        let mut t = from;
        for _ in 0..n {
            m.edge(t, true);
            m.edge(t + high, false);
            t += period;
        }
        t
    }

    #[test]
    fn brushed_duty_is_the_command_and_a_quiet_pin_its_level() {
        let p = Protocol::Brushed {
            frequency_hz: 32_000,
        };
        let mut m = PulseMeter::new();
        assert_eq!(m.command(&p, 1_000_000), Command::Stopped);
        // 25 % of 31.25 µs.
        let t = pulses(&mut m, 0, 7_812, 31_250, 10);
        match m.command(&p, t) {
            Command::Throttle(x) => assert!((x - 0.25).abs() < 1e-3, "{x}"),
            c => panic!("{c:?}"),
        }
        assert_eq!(m.command(&p, t + 1_000_000), Command::Stopped);
        m.edge(t + 1_000_000, true);
        assert_eq!(m.command(&p, t + 2_000_000), Command::Throttle(1.0));
        assert_eq!(m.take_starts().len(), 11);
    }

    #[test]
    fn pwm_and_oneshot_pulse_widths() {
        let pwm = Protocol::Pwm {
            rate_hz: 400,
            min_us: 1_000,
            max_us: 2_000,
        };
        let mut m = PulseMeter::new();
        let t = pulses(&mut m, 0, 1_500_000, 2_500_000, 3);
        assert_eq!(m.command(&pwm, t), Command::Throttle(0.5));
        assert_eq!(m.command(&pwm, t + 10_000_000), Command::Stopped);
        let mut o = PulseMeter::new();
        let t = pulses(&mut o, 0, 125_000, 1_000_000, 3);
        assert_eq!(o.command(&Protocol::OneShot125, t), Command::Stopped);
        let t = pulses(&mut o, t, 200_000, 1_000_000, 1);
        assert_eq!(o.command(&Protocol::OneShot125, t), Command::Throttle(0.6));
        assert_eq!(
            o.command(&Protocol::OneShot125, t + 6_000_000),
            Command::Stopped
        );
        assert_eq!(o.last_pulse(), Some((200_000, Some(1_000_000))));
    }

    #[test]
    fn a_board_without_power_stops_its_motors_at_once() {
        let brushed = Protocol::Brushed {
            frequency_hz: 32_000,
        };
        for (p, high, period) in [
            (brushed, 20_000, 31_250),
            (Protocol::OneShot125, 200_000, 1_000_000),
        ] {
            let mut m = PulseMeter::new();
            let t = pulses(&mut m, 0, high, period, 10);
            assert_ne!(m.command(&p, t), Command::Stopped, "{p:?} turning");
            m.power_lost(t);
            assert_eq!(m.command(&p, t), Command::Stopped, "{p:?} at the power cut");
        }
    }
}
