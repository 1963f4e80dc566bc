//! Re-derives the flight setup and re-solves the controller gains when a setting changes
//! (console or link), then hands both to the loop, which installs them while disarmed. The
//! f64 Riccati solves take ≈ 5.5 M instructions (≈ 35–45 ms at 168 MHz, tests/m4-bench
//! `flight_loop`): only ever done here, never in the loop. Arming waits for gains
//! (`FlightLoop` refuses without them), so a rejected design leaves the old gains in place.

use defmt::{info, warn};
use embassy_futures::select::{Either, select};
use embassy_time::{Duration, Timer};
use flight_core::pipeline::{Controllers, from_settings};

use super::supervisor::{Watched, check_in};
use crate::firmware::signals::{NEW_SETUP, SETTINGS, SETTINGS_CHANGED};

#[embassy_executor::task]
pub async fn gains_task() {
    loop {
        check_in(Watched::Gains);
        match select(
            SETTINGS_CHANGED.wait(),
            Timer::after(Duration::from_millis(100)),
        )
        .await
        {
            Either::First(()) => {}
            Either::Second(()) => continue,
        }
        let Some(settings) = SETTINGS.lock().await.as_ref().map(|(s, _)| s.clone()) else {
            continue;
        };
        let setup = match from_settings(&settings) {
            Ok(s) => s,
            Err(e) => {
                warn!("settings not flyable: {}", e);
                continue;
            }
        };
        check_in(Watched::Gains);
        match Controllers::design(&setup.control) {
            Ok(c) => {
                NEW_SETUP.signal((setup, c));
                info!("gains solved");
            }
            Err(e) => warn!("gain design failed: {}", e),
        }
    }
}
