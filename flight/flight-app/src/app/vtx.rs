//! When the VTX's select pins change: at boot (the first call), and after the settings'
//! band or channel changed (console, phone, the radio's device tool) — only while disarmed,
//! so the video never jumps channel in flight; a change made armed waits for the disarm.
//! The decision of which levels is `crate::vtx`.

use super::FlightApp;
use crate::vtx::{VtxChannel, VtxPins};

impl FlightApp {
    /// The pin levels to drive now, when they must change (the firmware of a board with a
    /// VTX calls this from a task that runs while disarmed, e.g. every console poll).
    pub fn take_vtx_pins(&mut self) -> Option<VtxPins> {
        let wanted = VtxChannel::from_settings(&self.live);
        let boot = self.vtx_applied.is_none();
        if self.vtx_applied == Some(wanted) || (!boot && self.armed()) {
            return None;
        }
        self.vtx_applied = Some(wanted);
        Some(wanted.pins())
    }

    /// The VTX channel the pins select (after [`FlightApp::take_vtx_pins`]).
    pub fn vtx_channel(&self) -> Option<VtxChannel> {
        self.vtx_applied
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::armed_in_the_air;
    use super::super::{ImuFault, STALL_RIDE_THROUGH_MS};
    use super::*;
    use crate::settings::Settings;
    use crate::vtx::Band;

    #[test]
    fn the_pins_follow_the_settings_at_boot_and_disarmed_only() {
        let mut settings = Settings::default();
        settings.set_text("vtx.band", "airwave").unwrap();
        settings.set_text("vtx.channel", "3").unwrap();
        let mut app = FlightApp::new(settings, 0).unwrap();
        // Boot: Airwave 3 (5780 MHz) = band code 3, channel code 2.
        let pins = app.take_vtx_pins().unwrap();
        assert!(pins.rf_s1 && pins.rf_s2, "band 3: both released");
        assert!(
            !pins.rf_ch1 && pins.rf_ch2 && !pins.rf_ch3,
            "channel code 0b010"
        );
        assert_eq!(app.vtx_channel().map(VtxChannel::frequency_mhz), Some(5780));
        assert_eq!(app.take_vtx_pins(), None, "nothing changed");

        // A change in flight waits: the video must not jump channel.
        let t = armed_in_the_air(&mut app);
        app.live.set_text("vtx.band", "b").unwrap();
        assert_eq!(app.take_vtx_pins(), None);
        assert_eq!(app.vtx_channel().map(|c| c.band), Some(Band::Airwave));
        // Disarmed (here by an IMU stall past its ride-through).
        let _ = app.on_imu_missing(t + STALL_RIDE_THROUGH_MS, ImuFault::Stalled);
        assert!(!app.armed());
        let pins = app.take_vtx_pins().unwrap();
        assert!(pins.rf_s1 && !pins.rf_s2, "band B = code 1");
        assert_eq!(app.vtx_channel().map(VtxChannel::frequency_mhz), Some(5771));
    }
}
