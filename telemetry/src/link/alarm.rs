//! When authentication failures run above what noise explains (spec §12.2, "Tag
//! failures"): both ends count the frames of their link whose tag failed; the count rises by
//! chance only when a corrupted packet passes the chip's CRC-16 and names the expected slot
//! (≈ 10⁻³ a second at 10 % packet loss at F700), so more than [`ALERT_FAILURES`] within
//! [`ALERT_WINDOW_US`] is a forger or a replayer at work, and the handset and the phone say
//! so.

/// Tag failures within [`ALERT_WINDOW_US`] that raise the alert.
pub const ALERT_FAILURES: u32 = 10;
/// The window the failures are counted in, µs.
pub const ALERT_WINDOW_US: u64 = 10_000_000;
/// Buckets of the window (one a second).
const BUCKETS: usize = 10;
const BUCKET_US: u64 = ALERT_WINDOW_US / BUCKETS as u64;

/// Tag failures per second over the last [`ALERT_WINDOW_US`].
#[derive(Clone, Debug, Default)]
pub struct TagAlarm {
    buckets: [u32; BUCKETS],
    /// The second the newest bucket counts.
    second: Option<u64>,
    /// The total at the last update.
    total: u32,
}

impl TagAlarm {
    /// The end's total of tag failures at `now_us`; whether they run above noise.
    pub fn update(&mut self, now_us: u64, total: u32) -> bool {
        let second = now_us / BUCKET_US;
        let new = total.saturating_sub(self.total);
        self.total = total;
        match self.second {
            Some(last) if second > last => {
                for _ in 0..(second - last).min(BUCKETS as u64) {
                    self.buckets.rotate_right(1);
                    if let Some(b) = self.buckets.first_mut() {
                        *b = 0;
                    }
                }
            }
            _ => {}
        }
        self.second = Some(second);
        if let Some(b) = self.buckets.first_mut() {
            *b = b.saturating_add(new);
        }
        self.alert()
    }

    /// Whether the failures of the window are above what noise explains.
    pub fn alert(&self) -> bool {
        self.buckets.iter().fold(0u32, |a, b| a.saturating_add(*b)) > ALERT_FAILURES
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_burst_raises_the_alert_for_the_window_and_noise_never_does() {
        let mut alarm = TagAlarm::default();
        // Noise: one failure a minute for an hour.
        for minute in 0..60u64 {
            assert!(!alarm.update(minute * 60_000_000, minute as u32));
        }
        // A forger: 20 wrong tags within a second.
        assert!(alarm.update(3_600_000_000, 59 + 20));
        assert!(alarm.update(3_605_000_000, 79), "still within the window");
        assert!(!alarm.update(3_611_000_000, 79), "the window has passed");
        // Eleven spread over ten seconds still alert; ten do not.
        let mut alarm = TagAlarm::default();
        for s in 0..10u64 {
            alarm.update(s * 1_000_000, s as u32 + 1);
        }
        assert!(!alarm.alert());
        assert!(alarm.update(9_500_000, 11));
    }
}
