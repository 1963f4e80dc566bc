//! Owns the RFM22B and runs what `FlightApp::next_link_step` says: a bind window the console
//! opened (the result to `on_bind_result`), the TauLink follower with the app as its hooks
//! (`on_link_step`: channels, setting changes, telemetry, check-in; keyed when a binding
//! phrase is stored) until the radio fails, a bind is asked for or the phrase changes, or —
//! never bound — nothing until the owner binds. With
//! `link.protocol` OpenLRSng the same, through flight-core's OpenLRSng receiver loops
//! (`run_openlrs_receiver` → `on_openlrs_step`, `openlrs_bind_window` →
//! `on_openlrs_bind_result`), the driver's parts lent to an OpenLRSng radio for the step.

use defmt::{info, warn};
use embassy_futures::select::{Either, select};
use embassy_time::{Delay, Duration, Instant};
use embedded_hal_bus::spi::ExclusiveDevice;
use flight_core::app::{FAILSAFE_US, LinkStep, openlrs_bind_window, run_openlrs_receiver};
use openlrs::radio::Radio as OpenLrsRadio;
use openlrs::rx::Receiver;
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
    let mut slot = Some(LinkRadio::new(
        Rfm22b::new_without_sdn(device, nirq, Delay),
        TxPower::MAX,
    ));
    let mut clock = EmbassyClock;
    loop {
        let step = with_app(|a| a.next_link_step()).unwrap_or(LinkStep::WaitForBind);
        if let LinkStep::BindOpenLrs { .. } | LinkStep::FollowOpenLrs { .. } = step {
            openlrs_step(&mut slot, step).await;
            continue;
        }
        let Some(radio) = slot.as_mut() else {
            return;
        };
        match step {
            LinkStep::Bind { band, window_us } => {
                let bind = bind_follower(radio, &mut clock, band, window_us);
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
                let run = run_follower(radio, &mut clock, &mut follower, &mut hooks);
                let failed = matches!(select(run, restart_due()).await, Either::First(Err(_)));
                with_app(|a| a.on_link_down());
                if failed {
                    // The radio failed (unplugged, bus fault): retry in a second.
                    warn!("link stopped: radio error");
                    idle(Duration::from_secs(1)).await;
                }
            }
            LinkStep::BindOpenLrs { .. } | LinkStep::FollowOpenLrs { .. } => {}
        }
    }
}

/// An OpenLRSng step: the driver's parts become an OpenLRSng radio for the step (the
/// OpenLRSng roles program the chip their own way) and go back afterwards.
async fn openlrs_step<SPI, IRQ>(
    slot: &mut Option<LinkRadio<SPI, IRQ, radio_rfm22b::NoPin, Delay>>,
    step: LinkStep,
) where
    SPI: embedded_hal_async::spi::SpiDevice,
    IRQ: embedded_hal_async::digital::Wait,
{
    let (LinkStep::BindOpenLrs { config, .. } | LinkStep::FollowOpenLrs { config, .. }) = step
    else {
        return;
    };
    let Some(link) = slot.take() else {
        return;
    };
    let (spi, irq, _, delay) = link.release().release();
    let now = || Instant::now().as_micros();
    let mut radio = OpenLrsRadio::new(spi, irq, delay, now, config.version, config.band);
    let failed = match step {
        LinkStep::BindOpenLrs { window_us, .. } => {
            let bind = openlrs_bind_window(&mut radio, config, window_us);
            let Either::First(result) = select(bind, keep_alive()).await;
            let bound = result.as_ref().ok().copied().flatten();
            if with_app(|a| a.on_openlrs_bind_result(bound.as_ref())).unwrap_or(false) {
                info!(
                    "bound to OpenLRSng link {:08x}",
                    bound.map_or(0, |d| d.rf_magic)
                );
            }
            result.is_err()
        }
        LinkStep::FollowOpenLrs { data, .. } => {
            let mut rx = Receiver::new(config, Some(data));
            let on_step = |now_us: u64, rx: &mut Receiver, events: &[_]| {
                with_app(|a| a.on_openlrs_step(now_us, rx, events));
            };
            let run = run_openlrs_receiver(&mut radio, &mut rx, on_step);
            // The check-in races too: a slow profile's lost-link dwell outlasts the IWDG.
            let waits = select(restart_due(), keep_alive());
            let failed = matches!(select(run, waits).await, Either::First(_));
            with_app(|a| a.on_link_down());
            failed
        }
        _ => false,
    };
    let (spi, irq, delay, _) = radio.release();
    *slot = Some(LinkRadio::new(
        Rfm22b::new_without_sdn(spi, irq, delay),
        TxPower::MAX,
    ));
    if failed {
        warn!("OpenLRSng link stopped: radio error");
        idle(Duration::from_secs(1)).await;
    }
}
