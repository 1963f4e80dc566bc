//! Re-derives the flight setup and re-solves the controller gains when the app asks
//! (`FlightApp::take_design_request`, after a setting change from the console or the link)
//! and hands both back; the app installs them while disarmed. The f64 Riccati solves take
//! ≈ 5.5 M instructions (≈ 35–45 ms at 168 MHz, tests/m4-bench `flight_loop`): only ever
//! done here, never in the loop. A rejected design leaves the old gains in place.

use defmt::{info, warn};
use embassy_time::{Duration, Timer};
use flight_app::gains;
use flight_app::pipeline::from_settings;

use crate::firmware::shared::with_app;

#[embassy_executor::task]
pub async fn gains_task() {
    loop {
        Timer::after(Duration::from_millis(100)).await;
        // Asking checks the task in with the watchdog.
        let Some(Some(settings)) = with_app(|a| a.take_design_request()) else {
            continue;
        };
        let setup = match from_settings(&settings) {
            Ok(s) => s,
            Err(e) => {
                warn!("settings not flyable: {}", e);
                continue;
            }
        };
        match gains::design(&setup.control) {
            Ok(c) => {
                with_app(|a| a.on_designed(setup, c));
                info!("gains solved");
            }
            Err(e) => warn!("gain design failed: {}", e),
        }
    }
}
