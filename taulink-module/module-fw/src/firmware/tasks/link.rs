//! Owns the RFM22B and runs the air link (`telemetry::link`) on it: probe the chip, then the
//! master loop (transmitter role) or the follower loop (receiver role) with the module core
//! as the loop's hook; a long press stops the loop and runs the bind exchange instead.
//!
//! Every slot (master) or step (follower) the hook hands the state machine to
//! `AirLink::on_master_slot` / `on_follower_step` (channels in, records both ways,
//! statistics) and lets the core fan received records and channels out (`App::poll_link`).

use core::sync::atomic::{AtomicU32, Ordering};

use defmt::{info, warn};
use embassy_futures::select::{Either, select};
use embassy_nrf::rng::Rng;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use embassy_time::{Delay, Duration, Timer};
use embedded_hal_bus::spi::ExclusiveDevice;
use module_core::air::radio::LinkRadio;
use module_core::air::{link_band, link_params, new_bind_params, settings_rate};
use module_core::settings::{Role, Settings};
use radio_rfm22b::Rfm22b;
use radio_rfm22b::TxPower;
use telemetry::channels::{Failsafe, FailsafeValues, MAX_CHANNELS};
use telemetry::link::PacketRadio;
use telemetry::link::core::follower::DEFAULT_FAILSAFE_US;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{FollowerHooks, bind_follower, run_follower};
use telemetry::link::master::{MasterHooks, bind_master, run_master};

use super::supervisor::{Watched, check_in};
use crate::firmware::board::Radio;
use crate::firmware::link_radio::EmbassyClock;
use crate::firmware::shared::{carry_out, now_ms, with_app};

/// How long one bind attempt lasts.
const BIND_TIMEOUT_US: u64 = 10_000_000;
/// The link loop counts as alive while its hook ran within this time. Longer than any one
/// step (the follower's acquisition dwell is one hop cycle), shorter than makes a hung radio
/// go unnoticed.
const HOOK_SILENCE_MS: u32 = 2_000;

/// A long press arrived while the link loop runs: stop it and bind.
static BIND: Signal<CriticalSectionRawMutex, ()> = Signal::new();
/// `now_ms` of the last hook call.
static LAST_HOOK_MS: AtomicU32 = AtomicU32::new(0);

/// Why a link session ended.
enum Stop {
    /// Bind requested.
    Bind,
    /// The radio failed; probe it again.
    RadioFailed,
}

#[embassy_executor::task]
pub async fn link_task(radio: Radio, boot_settings: Settings) {
    let Radio {
        spim,
        nsel,
        nirq,
        sdn,
        rng,
    } = radio;
    let Ok(device) = ExclusiveDevice::new_no_delay(spim, nsel);
    let mut rng = Rng::new_blocking(rng);
    let mut radio = LinkRadio::new(
        Rfm22b::new(device, nirq, sdn, Delay),
        TxPower::from_step(boot_settings.tx_power),
    );
    let mut clock = EmbassyClock;
    loop {
        check_in(Watched::Radio);
        // `reset` holds SDN high for 10 ms (full power-down, datasheet §3.3), waits out the
        // power-on reset, then software-resets and waits for chip-ready.
        let present = match radio.driver().reset().await {
            Ok(chip) => {
                info!("RFM22B found: Si4432 {}", chip.version);
                true
            }
            Err(e) => {
                warn!("radio reset/probe failed: {}", e);
                false
            }
        };
        carry_out(with_app(|app| app.on_radio_present(present)).flatten());
        if !present {
            keep_alive_for(Duration::from_secs(1)).await;
            continue;
        }
        let settings = with_app(|app| *app.settings()).unwrap_or(boot_settings);
        let stop = match link_params(&settings) {
            None => wait_for_bind_request().await,
            Some(params) => {
                info!("link {} as {}", params.rate, settings.role);
                let session = async {
                    match settings.role {
                        Role::Transmitter => {
                            let mut master = Master::new(params);
                            run_master(&mut radio, &mut clock, &mut master, &mut TxHooks).await
                        }
                        Role::Receiver => {
                            // Hold every channel: the PPM output applies the module's own
                            // failsafe setting (hold or stop pulses) once the link reports
                            // failsafe.
                            let hold = FailsafeValues([Failsafe::Hold; MAX_CHANNELS]);
                            let mut follower = Follower::new(params, hold, DEFAULT_FAILSAFE_US);
                            run_follower(&mut radio, &mut clock, &mut follower, &mut RxHooks).await
                        }
                    }
                };
                LAST_HOOK_MS.store(now_ms(), Ordering::Relaxed);
                match select(session, select(BIND.wait(), supervise())).await {
                    Either::First(Err(e)) => {
                        warn!("link radio failed: {}", e);
                        Stop::RadioFailed
                    }
                    Either::First(Ok(never)) => match never {},
                    Either::Second(Either::First(())) => Stop::Bind,
                    Either::Second(Either::Second(())) => {
                        warn!("link loop silent for {} ms", HOOK_SILENCE_MS);
                        Stop::RadioFailed
                    }
                }
            }
        };
        with_app(|app| app.link_mut().on_link_stopped());
        if let Stop::Bind = stop {
            bind(&mut radio, &mut clock, &settings, &mut rng).await;
        }
    }
}

/// Checks in for the radio task while the link loop's hook keeps running; returns when it
/// has been silent for [`HOOK_SILENCE_MS`].
async fn supervise() {
    loop {
        if now_ms().wrapping_sub(LAST_HOOK_MS.load(Ordering::Relaxed)) > HOOK_SILENCE_MS {
            return;
        }
        check_in(Watched::Radio);
        Timer::after(Duration::from_millis(50)).await;
    }
}

/// Unbound: idle (checking in) until a long press asks for a bind.
async fn wait_for_bind_request() -> Stop {
    loop {
        check_in(Watched::Radio);
        if with_app(|app| app.link_mut().take_bind_request()).unwrap_or(false) {
            return Stop::Bind;
        }
        Timer::after(Duration::from_millis(50)).await;
    }
}

async fn keep_alive_for(duration: Duration) {
    let _ = select(Timer::after(duration), keep_alive()).await;
}

async fn keep_alive() -> core::convert::Infallible {
    loop {
        check_in(Watched::Radio);
        Timer::after(Duration::from_millis(50)).await;
    }
}

/// One bind attempt in the settings' role; a success is saved through the core.
async fn bind<R: PacketRadio>(
    radio: &mut R,
    clock: &mut EmbassyClock,
    settings: &Settings,
    rng: &mut Rng<'static, embassy_nrf::mode::Blocking>,
) where
    R::Error: defmt::Format,
{
    info!("binding as {}", settings.role);
    let action = match settings.role {
        Role::Transmitter => {
            let params = new_bind_params(settings, rng.blocking_next_u32());
            match select(
                bind_master(radio, clock, &params, BIND_TIMEOUT_US),
                keep_alive(),
            )
            .await
            {
                Either::First(Ok(true)) => {
                    info!("bound: {:08x}", params.bind_id);
                    with_app(|app| app.on_bind_complete(params.bind_id))
                }
                Either::First(Ok(false)) => None,
                Either::First(Err(e)) => {
                    warn!("bind: radio failed: {}", e);
                    None
                }
                Either::Second(never) => match never {},
            }
        }
        Role::Receiver => {
            let band = link_band(settings.band);
            match select(
                bind_follower(radio, clock, band, BIND_TIMEOUT_US),
                keep_alive(),
            )
            .await
            {
                Either::First(Ok(Some(params))) => {
                    info!("bound: {:08x} at {}", params.bind_id, params.rate);
                    if settings_rate(params.rate, settings.rate).is_none() {
                        warn!("no rate setting gives {}: keeping the setting", params.rate);
                    }
                    with_app(|app| app.on_bind_offer_accepted(&params))
                }
                Either::First(Ok(None)) => None,
                Either::First(Err(e)) => {
                    warn!("bind: radio failed: {}", e);
                    None
                }
                Either::Second(never) => match never {},
            }
        }
    };
    match action {
        Some(action) => carry_out(Some(action)),
        None => {
            info!("bind: no peer");
            carry_out(with_app(|app| app.on_bind_failed()).flatten());
        }
    }
}

/// The master's hook: the module core's channels and records in, telemetry out.
struct TxHooks;

impl MasterHooks for TxHooks {
    fn on_slot(&mut self, now_us: u64, master: &mut Master) {
        LAST_HOOK_MS.store(now_ms(), Ordering::Relaxed);
        let bind = with_app(|app| {
            app.link_mut().on_master_slot(now_us, master);
            app.poll_link();
            app.link_mut().take_bind_request()
        });
        if bind == Some(true) {
            BIND.signal(());
        }
    }
}

/// The follower's hook: received channels to the PPM output, records both ways.
struct RxHooks;

impl FollowerHooks for RxHooks {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        LAST_HOOK_MS.store(now_ms(), Ordering::Relaxed);
        let bind = with_app(|app| {
            app.link_mut().on_follower_step(now_us, follower);
            app.poll_link();
            app.link_mut().take_bind_request()
        });
        if bind == Some(true) {
            BIND.signal(());
        }
    }
}
