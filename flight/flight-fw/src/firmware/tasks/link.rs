//! Owns the RFM22B and runs what `FlightApp::next_link_step` says: a bind window the console
//! opened (the result to `on_bind_result`), the TauLink follower with the app as its hooks
//! (`on_link_step`: channels, setting changes, telemetry, check-in; keyed when a binding
//! phrase is stored) until the radio fails, a bind is asked for or the phrase changes, or —
//! never bound — nothing until the owner binds.

use defmt::{info, warn};
use embassy_futures::select::{Either, select};
use embassy_time::{Delay, Duration};
use embedded_hal_bus::spi::ExclusiveDevice;
use flight_core::app::{FAILSAFE_US, LinkStep};
use radio_rfm22b::{Rfm22b, TxPower};
use telemetry::link::core::Follower;
use telemetry::link::follower::{FollowerHooks, bind_follower, run_follower};

use crate::firmware::board::Radio;
use crate::firmware::link_radio::{EmbassyClock, LinkRadio, idle, keep_alive, restart_due};
use crate::firmware::shared::with_app;

/// The follower's hooks: straight into the app.
struct AppHooks;

impl FollowerHooks for AppHooks {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        with_app(|a| a.on_link_step(now_us, follower));
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
        match with_app(|a| a.next_link_step()).unwrap_or(LinkStep::WaitForBind) {
            LinkStep::Bind { band, window_us } => {
                let bind = bind_follower(&mut radio, &mut clock, band, window_us);
                let result = select(bind, keep_alive()).await;
                let Either::First(result) = result;
                let offered = result.as_ref().ok().copied().flatten();
                if with_app(|a| a.on_bind_result(offered.as_ref())).unwrap_or(false) {
                    info!("bound to link {:08x}", offered.map_or(0, |p| p.bind_id));
                }
                if let Err(e) = result {
                    warn!("radio: {}", e);
                    idle(Duration::from_secs(1)).await;
                }
            }
            LinkStep::WaitForBind => restart_due().await,
            LinkStep::Follow(params) => {
                // Keyed with the binding phrase's key when one is stored.
                let Some(mut follower) = with_app(|a| a.follower(params, FAILSAFE_US)) else {
                    idle(Duration::from_secs(1)).await;
                    continue;
                };
                let mut hooks = AppHooks;
                let run = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks);
                let failed = matches!(select(run, restart_due()).await, Either::First(Err(_)));
                with_app(|a| a.on_link_down());
                if failed {
                    // The radio failed (unplugged, bus fault): retry in a second.
                    warn!("link stopped: radio error");
                    idle(Duration::from_secs(1)).await;
                }
            }
        }
    }
}
