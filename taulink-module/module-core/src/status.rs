//! Status LED patterns: what the single LED says about the module, as a repeating list of
//! on/off durations that the LED task plays.

/// What the module is doing, as far as the pilot needs to know.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkState {
    /// Starting up or the radio is missing.
    NoRadio,
    /// No bind ID stored yet.
    Unbound,
    /// Bind in progress.
    Binding,
    /// Bound, no answer from the other end yet.
    Searching,
    /// Link up.
    Connected,
    /// The link was up and is lost (failsafe).
    Failsafe,
    /// The module's supply (the radio battery) is low: three short blinks, then a pause.
    LowBattery,
}

impl LinkState {
    /// The LED pattern as alternating on/off durations in ms, starting with "on", played in
    /// a loop. Distinct rhythms rather than rates: a double blink (failsafe) and a single
    /// flash (no radio) read at a glance even in sunlight.
    pub const fn pattern(self) -> &'static [u32] {
        match self {
            LinkState::NoRadio => &[50, 1950],
            LinkState::Unbound => &[1000, 1000],
            LinkState::Binding => &[100, 100],
            LinkState::Searching => &[500, 500],
            LinkState::Connected => &[1000],
            LinkState::Failsafe => &[100, 150, 100, 650],
            LinkState::LowBattery => &[100, 100, 100, 100, 100, 1500],
        }
    }

    /// The LED level `elapsed_ms` after the pattern started.
    pub fn level_at(self, elapsed_ms: u32) -> bool {
        let pattern = self.pattern();
        let period: u32 = pattern.iter().sum();
        if period == 0 {
            return false;
        }
        let mut phase = elapsed_ms % period;
        for (index, duration) in pattern.iter().enumerate() {
            if phase < *duration {
                return index % 2 == 0;
            }
            phase -= duration;
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_play_as_written() {
        assert!(LinkState::Connected.level_at(0));
        assert!(LinkState::Connected.level_at(123_456));
        assert!(LinkState::Searching.level_at(499));
        assert!(!LinkState::Searching.level_at(500));
        assert!(LinkState::Searching.level_at(1_000));
        // Failsafe: on 0–99, off 100–249, on 250–349, off 350–999.
        let failsafe: Vec<bool> = [0, 99, 100, 249, 250, 349, 350, 999, 1000]
            .iter()
            .map(|t| LinkState::Failsafe.level_at(*t))
            .collect();
        assert_eq!(
            failsafe,
            [true, true, false, false, true, true, false, false, true]
        );
        assert!(LinkState::NoRadio.level_at(49) && !LinkState::NoRadio.level_at(50));
    }

    #[test]
    fn every_pattern_has_a_one_to_two_second_period() {
        for state in [
            LinkState::NoRadio,
            LinkState::Unbound,
            LinkState::Binding,
            LinkState::Searching,
            LinkState::Failsafe,
        ] {
            let period: u32 = state.pattern().iter().sum();
            assert!((200..=2_000).contains(&period), "{state:?}: {period} ms");
            assert_eq!(
                state.pattern().len() % 2,
                0,
                "{state:?} ends with an off time"
            );
        }
    }
}
