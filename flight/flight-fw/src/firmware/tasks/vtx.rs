//! The BrushedSparky's VTX select pins (`board::VtxPins`): set at boot from the settings
//! and again after a change of `vtx.band` / `vtx.channel` (console, phone, the radio's
//! device tool) while disarmed — the app decides when and which levels
//! (`FlightApp::take_vtx_pins`, `flight_app::vtx`). The Sparky2 has no VTX.

use defmt::info;
use embassy_time::{Duration, Timer};

use crate::firmware::board::VtxPins;
use crate::firmware::shared::with_app;

/// How often a changed channel is looked for (a pilot waits this long at most).
const POLL_MS: u64 = 100;

#[embassy_executor::task]
pub async fn vtx_task(mut pins: VtxPins) {
    with_app(|a| a.set_vtx_present(true));
    loop {
        if let Some(Some(levels)) = with_app(|a| a.take_vtx_pins()) {
            pins.set(levels);
            if let Some(Some(channel)) = with_app(|a| a.vtx_channel()) {
                info!(
                    "VTX {} {} ({} MHz)",
                    channel.band.label(),
                    channel.channel,
                    channel.frequency_mhz()
                );
            }
        }
        Timer::after(Duration::from_millis(POLL_MS)).await;
    }
}
