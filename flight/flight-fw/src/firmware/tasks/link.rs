//! Owns the RFM22B and runs the TauLink follower on it (`telemetry::link`); after every
//! step the follower hands itself to `FlightApp::on_link_step` (channels, setting changes,
//! telemetry, watchdog check-in). For `BIND_WINDOW_US` after boot the follower listens for
//! a bind offer first; a bind goes to `FlightApp::on_bound` (stored and saved). A radio
//! error ends the follower: the app sees the link down, and the task retries in a second.

use defmt::{info, warn};
use embassy_futures::select::{Either, select};
use embassy_time::{Delay, Duration, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use flight_core::app::{BIND_WINDOW_US, FAILSAFE_US};
use radio_rfm22b::{Rfm22b, TxPower};
use telemetry::channels::FailsafeValues;
use telemetry::link::core::Follower;
use telemetry::link::follower::{FollowerHooks, bind_follower, run_follower};

use crate::firmware::board::Radio;
use crate::firmware::link_radio::{EmbassyClock, LinkRadio};
use crate::firmware::shared::with_app;

/// The follower's hooks: straight into the app.
struct AppHooks;

impl FollowerHooks for AppHooks {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        with_app(|a| a.on_link_step(now_us, follower));
    }
}

/// Waits `d`, checking in with the watchdog every 50 ms.
async fn idle(d: Duration) {
    let _ = select(Timer::after(d), keep_alive()).await;
}

async fn keep_alive() -> core::convert::Infallible {
    loop {
        with_app(|a| a.on_link_idle());
        Timer::after(Duration::from_millis(50)).await;
    }
}

#[embassy_executor::task]
pub async fn link_task(radio: Radio) {
    let Radio { spi, nsel, nirq } = radio;
    let Ok(device) = ExclusiveDevice::new_no_delay(spi, nsel);
    // SDN is tied low on these boards: software reset only.
    let mut radio = LinkRadio::new(Rfm22b::new_without_sdn(device, nirq, Delay), TxPower::MAX);
    let mut clock = EmbassyClock;
    let Some(mut params) = with_app(|a| a.link_params()) else {
        return;
    };
    let mut bind_window = true;
    loop {
        if bind_window {
            let bind = bind_follower(&mut radio, &mut clock, params.band, BIND_WINDOW_US);
            match select(bind, keep_alive()).await {
                Either::First(Ok(Some(offered))) => {
                    info!("bound to link {:08x}", offered.bind_id);
                    params = offered;
                    with_app(|a| a.on_bound(&offered));
                }
                Either::First(Ok(None)) => {}
                Either::First(Err(e)) => {
                    warn!("radio: {}", e);
                    idle(Duration::from_secs(1)).await;
                    continue;
                }
            }
            bind_window = false;
        }
        let mut follower = Follower::new(params, FailsafeValues::default(), FAILSAFE_US);
        let Err(e) = run_follower(&mut radio, &mut clock, &mut follower, &mut AppHooks).await;
        warn!("link stopped: {}", e);
        with_app(|a| a.on_link_down());
        idle(Duration::from_secs(1)).await;
    }
}
