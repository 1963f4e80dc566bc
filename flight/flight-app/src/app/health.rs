//! The board's standing as the firmware reports it and the pilot sees it: what the boot found
//! (a clock fallback, an RNG fallback, a resumed flight), whether a USB host has the console
//! (arming is refused then: `supervisor::Inputs::usb_connected` says why), the flight loop's
//! missed samples and overruns, the `Health` telemetry message and the status LEDs.

use telemetry::messages::Health;

use super::FlightApp;

/// What the firmware found at boot, told to the app once.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BootFacts {
    /// The crystal did not start: the clocks run from the internal RC (USB may not work).
    pub clock_fallback: bool,
    /// The hardware RNG gave nothing within its limit: the boot's seeds came from a weaker
    /// source.
    pub rng_fallback: bool,
}

/// Counters change every missed sample; a `Health` message for them alone goes at most
/// this often, µs (a flag change goes at once). A standing flag is said again this often:
/// the link does not acknowledge messages, so a lost one costs this long, not the news.
pub const HEALTH_PERIOD_US: u64 = 1_000_000;

/// The standing the app keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(super) struct BoardState {
    pub(super) boot: BootFacts,
    pub(super) usb_connected: bool,
    /// The last `Health` sent and when (link clock, µs); nothing sent while all is well.
    last_sent: Option<(Health, u64)>,
}

/// The status LEDs (both boards: PB4 orange alarm, PB6 blue link; the heartbeat on PB5 is
/// the heartbeat task's own blink).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Leds {
    /// On while a fault stands or the failsafe flies.
    pub alarm: bool,
    /// On while the link delivers.
    pub link: bool,
}

impl FlightApp {
    /// What the boot found (the firmware, once, before the tasks start).
    pub fn on_boot_facts(&mut self, facts: BootFacts) {
        self.board.boot = facts;
    }

    /// A USB host connected (the board enumerated) or went: arming is refused while one is.
    pub fn on_usb(&mut self, connected: bool) {
        self.board.usb_connected = connected;
    }

    /// The firmware's health: flags and the loop's counters.
    pub fn health(&self) -> Health {
        let flag = |on: bool, bit: u8| if on { bit } else { 0 };
        let loop_health = self.loop_health();
        Health {
            flags: flag(self.baro.failed(), Health::BARO_FAILED)
                | flag(self.board.boot.clock_fallback, Health::CLOCK_FALLBACK)
                | flag(self.resumed.is_some(), Health::RESUMED)
                | flag(self.board.boot.rng_fallback, Health::RNG_FALLBACK)
                | flag(self.board.usb_connected, Health::USB_CONNECTED),
            imu_missed: u16::try_from(loop_health.missed).unwrap_or(u16::MAX),
            loop_overruns: u16::try_from(loop_health.overruns).unwrap_or(u16::MAX),
        }
    }

    /// The `Health` message due at `now_us` (link clock): at once when a flag changed, once
    /// per [`HEALTH_PERIOD_US`] while a flag stands or when the counters changed; nothing
    /// while all is well from boot on.
    pub(super) fn take_health_report(&mut self, now_us: u64) -> Option<Health> {
        let now = self.health();
        let (last, at) = self.board.last_sent.unwrap_or((Health::default(), now_us));
        let period = now_us.saturating_sub(at) >= HEALTH_PERIOD_US;
        let due = now.flags != last.flags
            || (period && (now != last || now.flags != 0))
            || (now != last && self.board.last_sent.is_none());
        if !due {
            return None;
        }
        self.board.last_sent = Some((now, now_us));
        Some(now)
    }

    /// What the status LEDs show now.
    pub fn leds(&self) -> Leds {
        let h = self.health();
        let faults = Health::BARO_FAILED | Health::CLOCK_FALLBACK | Health::RNG_FALLBACK;
        let failsafe = self.last_output().is_some_and(|o| o.failsafe);
        let battery_critical = self.battery_critical;
        Leds {
            alarm: h.flags & faults != 0
                || self.imu_fault().is_some()
                || self.settings_problem.is_some()
                || battery_critical
                || failsafe,
            link: self.link_input.up,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Settings;

    #[test]
    fn health_goes_out_on_a_flag_change_and_counters_once_a_second() {
        let mut app = FlightApp::new(Settings::default(), 0).unwrap();
        assert_eq!(app.take_health_report(0), None, "all well: nothing to say");
        app.on_usb(true);
        let h = app.take_health_report(10).unwrap();
        assert_eq!(h.flags, Health::USB_CONNECTED);
        assert_eq!(app.take_health_report(20), None);
        for t in 0..5 {
            app.on_baro(t * 20, None);
        }
        assert_eq!(
            app.take_health_report(30).unwrap().flags,
            Health::USB_CONNECTED | Health::BARO_FAILED
        );
        app.on_boot_facts(BootFacts {
            clock_fallback: true,
            rng_fallback: false,
        });
        assert!(app.take_health_report(40).is_some());
        // A standing flag is said again a period later, in case the message was lost.
        assert_eq!(app.take_health_report(50), None);
        let again = app.take_health_report(40 + HEALTH_PERIOD_US).unwrap();
        assert_ne!(again.flags & Health::CLOCK_FALLBACK, 0);
        assert_eq!(app.take_health_report(50 + HEALTH_PERIOD_US), None);
    }

    #[test]
    fn the_leds_show_the_link_and_a_standing_fault() {
        let mut app = FlightApp::new(Settings::default(), 0).unwrap();
        assert_eq!(
            app.leds(),
            Leds {
                alarm: false,
                link: false
            }
        );
        app.link_input.up = true;
        assert!(app.leds().link);
        for t in 0..5 {
            app.on_baro(t * 20, None);
        }
        assert!(app.leds().alarm);
    }
}
