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
        if self.vtx_applied == Some(wanted) || (!boot && self.flight.armed()) {
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
