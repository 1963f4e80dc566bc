//! The flight loop's timing as seen on the pins: from the MPU-9250's data-ready edge (INT
//! rises) to the start of the first motor pulse that carries a new command (a pulse whose
//! width differs from that motor's previous one: the loop's output reached the timer). A
//! OneShot125 pulse starts when the loop fires it; a free-running brushed or PWM output
//! shows the new duty at its next period, so there the figure includes up to one PWM
//! period of waiting (31 µs at 32 kHz). With the gyro's noise every loop moves the motors,
//! so nearly every sample yields a latency; a data-ready with no new pulse before the next
//! one counts as no output for that sample.

/// Widths closer than this are the same command (a timer tick at 168 MHz is 6 ns).
const SAME_WIDTH_NS: u64 = 20;

/// The running measurement.
#[derive(Debug, Clone, Default)]
pub struct LoopTiming {
    /// The latest data-ready not yet answered.
    pending: Option<u64>,
    /// Each motor's last pulse width.
    last_width: [Option<u64>; 4],
    /// Latencies, ns.
    latencies: Vec<u64>,
    /// Data-ready edges no new pulse answered.
    unanswered: u64,
}

impl LoopTiming {
    /// Data-ready rises and motor pulses (start, width, motor) of one step, each in time
    /// order.
    pub fn feed(&mut self, rises: &[u64], pulses: &[(u64, u64, usize)]) {
        let mut r = rises.iter().peekable();
        for &(start, width, motor) in pulses {
            while let Some(&&t) = r.peek() {
                if t > start {
                    break;
                }
                if self.pending.replace(t).is_some() {
                    self.unanswered += 1;
                }
                r.next();
            }
            let Some(last) = self.last_width.get_mut(motor) else {
                continue;
            };
            let changed = last.is_none_or(|w| w.abs_diff(width) > SAME_WIDTH_NS);
            *last = Some(width);
            if changed && let Some(t) = self.pending.take() {
                self.latencies.push(start - t);
            }
        }
        for &t in r {
            if self.pending.replace(t).is_some() {
                self.unanswered += 1;
            }
        }
    }

    /// Data-ready edges that had no new motor pulse before the next one.
    pub fn unanswered(&self) -> u64 {
        self.unanswered
    }

    /// The latency at quantile `q` (0…1), µs (None: nothing measured).
    pub fn quantile_us(&self, q: f64) -> Option<f64> {
        let mut v = self.latencies.clone();
        v.sort_unstable();
        let i = ((v.len().saturating_sub(1)) as f64 * q.clamp(0.0, 1.0)).round() as usize;
        v.get(i).map(|ns| *ns as f64 / 1e3)
    }

    /// The jitter: p99 of the latency minus its median, µs.
    pub fn jitter_p99_us(&self) -> Option<f64> {
        Some(self.quantile_us(0.99)? - self.quantile_us(0.5)?)
    }

    /// How many latencies were measured.
    pub fn count(&self) -> usize {
        self.latencies.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_to_the_first_changed_pulse_and_its_spread() {
        let mut t = LoopTiming::default();
        let mut rises = Vec::new();
        let mut pulses = Vec::new();
        for k in 0..100u64 {
            let int = k * 1_000_000;
            rises.push(int);
            // A PWM period at +3 µs with the old width, then the new one at +10 … +12 µs.
            pulses.push((int + 3_000, 10_000 + 100 * (k % 2), 0));
            pulses.push((int + 10_000 + (k % 3) * 1_000, 20_000 + 100 * k, 1));
        }
        t.feed(&rises, &pulses);
        assert_eq!(t.count(), 100);
        assert_eq!(
            t.quantile_us(0.0),
            Some(3.0),
            "motor 0 changes every loop from the 2nd"
        );
        // A sample whose loop moves no motor: unanswered.
        let mut t = LoopTiming::default();
        t.feed(
            &[0, 1_000_000, 2_000_000],
            &[(5_000, 10_000, 0), (2_005_000, 10_000, 0)],
        );
        assert_eq!(t.count(), 1);
        assert_eq!(t.unanswered(), 1);
        assert_eq!(t.jitter_p99_us(), Some(0.0));
    }
}
