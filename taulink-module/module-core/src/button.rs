//! The bind button: debounced, with short and long presses, fed with periodic samples.
//!
//! A raw level must hold for `debounce_ms` before it counts (contact bounce lasts a few ms).
//! Holding the button `long_press_ms` fires `LongPress` once, while still held, so the
//! user sees the module react (binding starts) without letting go; releasing before that is
//! a `ShortPress`.

/// Timing of the button.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ButtonConfig {
    /// A level must be stable this long.
    pub debounce_ms: u32,
    /// Held this long is a long press.
    pub long_press_ms: u32,
}

impl Default for ButtonConfig {
    fn default() -> Self {
        Self {
            debounce_ms: 30,
            long_press_ms: 3_000,
        }
    }
}

/// What a press was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ButtonEvent {
    /// Pressed and released before the long-press time.
    ShortPress,
    /// Held for the long-press time (fired while still held).
    LongPress,
}

/// The debouncer and press classifier.
#[derive(Debug, Clone)]
pub struct Button {
    config: ButtonConfig,
    raw: bool,
    raw_since_ms: u32,
    stable: bool,
    pressed_since_ms: u32,
    long_fired: bool,
}

impl Button {
    /// A released button at `now_ms`.
    pub fn new(config: ButtonConfig, now_ms: u32) -> Self {
        Self {
            config,
            raw: false,
            raw_since_ms: now_ms,
            stable: false,
            pressed_since_ms: now_ms,
            long_fired: false,
        }
    }

    /// The debounced state.
    pub fn is_pressed(&self) -> bool {
        self.stable
    }

    /// One sample of the (active) button level at `now_ms`.
    pub fn on_sample(&mut self, pressed: bool, now_ms: u32) -> Option<ButtonEvent> {
        if pressed != self.raw {
            self.raw = pressed;
            self.raw_since_ms = now_ms;
        }
        if self.raw != self.stable
            && now_ms.wrapping_sub(self.raw_since_ms) >= self.config.debounce_ms
        {
            self.stable = self.raw;
            if self.stable {
                // The press began when the level first went down, not after the debounce.
                self.pressed_since_ms = self.raw_since_ms;
                self.long_fired = false;
            } else if !self.long_fired {
                return Some(ButtonEvent::ShortPress);
            }
        }
        if self.stable
            && !self.long_fired
            && now_ms.wrapping_sub(self.pressed_since_ms) >= self.config.long_press_ms
        {
            self.long_fired = true;
            return Some(ButtonEvent::LongPress);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples every 10 ms from `levels` (one per sample); returns (time, event).
    fn run(levels: &[bool]) -> Vec<(u32, ButtonEvent)> {
        let mut button = Button::new(ButtonConfig::default(), 0);
        levels
            .iter()
            .enumerate()
            .filter_map(|(i, level)| {
                let now = 10 * i as u32;
                button.on_sample(*level, now).map(|e| (now, e))
            })
            .collect()
    }

    fn held(ms: usize) -> Vec<bool> {
        vec![true; ms / 10]
    }

    #[test]
    fn short_press_on_release() {
        let mut levels = vec![false; 5];
        levels.extend(held(500));
        levels.extend(vec![false; 10]);
        // Pressed at 50 ms, released at 550 ms, stable released 30 ms later.
        assert_eq!(run(&levels), vec![(580, ButtonEvent::ShortPress)]);
    }

    #[test]
    fn long_press_fires_once_while_held() {
        let mut levels = vec![false; 5];
        levels.extend(held(5_000));
        levels.extend(vec![false; 10]);
        assert_eq!(run(&levels), vec![(3_050, ButtonEvent::LongPress)]);
    }

    #[test]
    fn bounce_is_ignored() {
        // 20 ms of chatter at press and release, then a 1 s press.
        let mut levels = vec![false, true, false, true, false, true];
        levels.extend(held(1_000));
        levels.extend([false, true, false]);
        levels.extend(vec![false; 10]);
        let events = run(&levels);
        assert_eq!(events.len(), 1);
        assert_eq!(events[0].1, ButtonEvent::ShortPress);
        // A 20 ms glitch never registers.
        let mut glitch = vec![false; 5];
        glitch.extend(held(20));
        glitch.extend(vec![false; 10]);
        assert!(run(&glitch).is_empty());
    }
}
