//! Owns the RFM22B and runs the TauLink follower on it (`telemetry::link`); after every
//! step the follower hands itself to `FlightApp::on_link_step` (channels, setting changes,
//! telemetry, watchdog check-in). Binding is explicit: only after the console's `bind`
//! (`FlightApp::take_bind_request`) does the task listen for a bind offer, for the window
//! the app gives, and the result goes to `FlightApp::on_bind_result` (stored and saved). A
//! controller never bound runs no link. A radio error ends the follower: the app sees the
//! link down, and the task retries in a second.

use defmt::{info, warn};
use embassy_futures::select::{Either, select};
use embassy_time::{Delay, Duration, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use flight_core::app::FAILSAFE_US;
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

/// Resolves when the console asked for a bind (polled every 50 ms, checking in).
async fn bind_requested() {
    loop {
        if with_app(|a| a.bind_requested()).unwrap_or(false) {
            return;
        }
        with_app(|a| a.on_link_idle());
        Timer::after(Duration::from_millis(50)).await;
    }
}

#[embassy_executor::task]
pub async fn link_task(radio: Radio) {
    let Radio { spi, nsel, nirq } = radio;
    let Ok(device) = ExclusiveDevice::new_no_delay(spi, nsel);
    // SDN is tied low on these boards: software reset only. Bind mode drops to the lowest
    // power step by itself (`RadioConfig::reduced_power`).
    let mut radio = LinkRadio::new(Rfm22b::new_without_sdn(device, nirq, Delay), TxPower::MAX);
    let mut clock = EmbassyClock;
    loop {
        if let Some((band, window_us)) = with_app(|a| a.take_bind_request()).flatten() {
            let bind = bind_follower(&mut radio, &mut clock, band, window_us);
            match select(bind, keep_alive()).await {
                Either::First(Ok(offered)) => {
                    if with_app(|a| a.on_bind_result(offered.as_ref())).unwrap_or(false) {
                        info!("bound to link {:08x}", offered.map_or(0, |p| p.bind_id));
                    }
                }
                Either::First(Err(e)) => {
                    warn!("radio: {}", e);
                    with_app(|a| a.on_bind_result(None));
                    idle(Duration::from_secs(1)).await;
                }
            }
            continue;
        }
        // Never bound: no link runs until the owner binds.
        let Some(params) = with_app(|a| a.link_params()).flatten() else {
            bind_requested().await;
            continue;
        };
        let mut follower = Follower::new(params, FailsafeValues::default(), FAILSAFE_US);
        let mut hooks = AppHooks;
        let run = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks);
        match select(run, bind_requested()).await {
            Either::First(Err(e)) => {
                warn!("link stopped: {}", e);
                with_app(|a| a.on_link_down());
                idle(Duration::from_secs(1)).await;
            }
            // The console's `bind` (disarmed): the follower stops, the window opens.
            Either::Second(()) => {
                with_app(|a| a.on_link_down());
            }
        }
    }
}
