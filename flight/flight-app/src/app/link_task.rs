//! The flight link task's body, shared by the firmware and the simulator so neither writes
//! it twice: one [`run_link_step`] asks [`FlightApp::next_link_step`] what to run and runs
//! it on the RFM22B ([`DualRadio`]: TauLink's `LinkRadio`, or the chip lent to an OpenLRSng
//! radio) — a bind window, the follower with the app as its hooks, OpenLRSng's receiver or
//! bind window, or nothing until a bind is asked for — checking the link task in with the
//! watchdog policy every [`LINK_POLL_US`] whenever nothing else does, then reports the
//! outcome to the app. After a radio failure it waits [`RADIO_RETRY_US`] (checking in)
//! before the next step, so an unplugged radio costs a retry a second, not a busy loop.
//!
//! The adapter only supplies the parts: the app behind its lock ([`AppAccess`]), the
//! driver and the link's clock, and logs the [`LinkEvent`] a step returns.

use core::cell::RefCell;
use core::convert::Infallible;

use embassy_futures::select::{Either, select};
use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;
use openlrs::dual::DualRadio;
use openlrs::radio::Clock;
use openlrs::rx::Receiver;
use telemetry::link::LinkClock;
use telemetry::link::core::Follower;
use telemetry::link::follower::{FollowerBind, FollowerHooks, bind_follower, run_follower};

use super::{FlightApp, LinkStep, openlrs_bind_window, run_openlrs_receiver};

/// How often the link task checks in while it waits outside the follower's hooks, µs.
pub const LINK_POLL_US: u64 = 50_000;
/// After the radio failed (unplugged, bus fault, stuck nIRQ), the next step starts this much
/// later, µs.
pub const RADIO_RETRY_US: u64 = 1_000_000;

/// How the link task reaches the app: the firmware's critical-section mutex, the
/// simulator's `RefCell`. Every call is short and never awaits; `None` when the app is
/// not there (not installed yet, or busy).
pub trait AppAccess {
    /// Runs `f` on the app.
    fn with_app<R>(&self, f: impl FnOnce(&mut FlightApp) -> R) -> Option<R>;
}

impl AppAccess for RefCell<FlightApp> {
    fn with_app<R>(&self, f: impl FnOnce(&mut FlightApp) -> R) -> Option<R> {
        self.try_borrow_mut().ok().map(|mut app| f(&mut app))
    }
}

/// What a link step did worth telling the owner (the firmware logs it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkEvent {
    /// A TauLink bind in the console's window was stored.
    Bound {
        /// The link's bind ID.
        bind_id: u32,
        /// With an agreed key (else an unauthenticated link).
        authenticated: bool,
    },
    /// An offer in the console's window was not bound, and why.
    BindRefused(telemetry::link::BindRefusal),
    /// An OpenLRSng bind in the console's window was stored.
    BoundOpenLrs {
        /// The transmitter's RF magic.
        rf_magic: u32,
    },
    /// The radio failed; the task waited [`RADIO_RETRY_US`].
    RadioFailed,
}

/// The follower's hooks: straight into the app.
struct Hooks<'a, A>(&'a A);

impl<A: AppAccess> FollowerHooks for Hooks<'_, A> {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        self.0.with_app(|a| a.on_link_step(now_us, follower));
    }
}

/// Checks the link task in every [`LINK_POLL_US`], forever (raced against a bounded wait).
async fn keep_alive<A: AppAccess, K: LinkClock>(app: &A, mut clock: K) -> Infallible {
    loop {
        app.with_app(|a| a.on_link_idle());
        let next = clock.now_us().saturating_add(LINK_POLL_US);
        clock.sleep_until_us(next).await;
    }
}

/// Resolves when the link must restart (a bind asked for, the binding phrase changed),
/// checking in every [`LINK_POLL_US`].
async fn restart_due<A: AppAccess, K: LinkClock>(app: &A, mut clock: K) {
    loop {
        if app.with_app(|a| a.link_restart_due()).unwrap_or(false) {
            return;
        }
        app.with_app(|a| a.on_link_idle());
        let next = clock.now_us().saturating_add(LINK_POLL_US);
        clock.sleep_until_us(next).await;
    }
}

/// Waits `us`, checking in.
async fn idle<A: AppAccess, K: LinkClock + Clone>(app: &A, clock: &K, us: u64) {
    let mut sleeper = clock.clone();
    let until = sleeper.now_us().saturating_add(us);
    let _ = select(
        sleeper.sleep_until_us(until),
        keep_alive(app, clock.clone()),
    )
    .await;
}

/// One step of the link task (see the module doc); the firmware and the simulator call it
/// in a loop. `failsafe_us`: the follower's silence timeout
/// ([`super::FAILSAFE_US`] on the firmware).
pub async fn run_link_step<A, SPI, IRQ, SDN, D, C, K>(
    app: &A,
    chip: &mut DualRadio<SPI, IRQ, SDN, D, C>,
    clock: &mut K,
    failsafe_us: u64,
) -> Option<LinkEvent>
where
    A: AppAccess,
    SPI: SpiDevice,
    IRQ: Wait,
    SDN: OutputPin,
    D: DelayNs,
    C: Clock,
    K: LinkClock + Clone,
{
    let step = app
        .with_app(|a| a.next_link_step())
        .unwrap_or(LinkStep::WaitForBind);
    let ticker = clock.clone();
    let (event, failed) = match step {
        LinkStep::WaitForBind => {
            restart_due(app, ticker).await;
            (None, false)
        }
        LinkStep::Bind(request) => match chip.taulink() {
            Some(radio) => {
                let auth = request.auth();
                let bind = bind_follower(
                    radio,
                    clock,
                    request.band,
                    &auth,
                    &request.random,
                    request.window_us,
                );
                let Either::First(result) = select(bind, keep_alive(app, ticker)).await;
                let outcome = result
                    .as_ref()
                    .ok()
                    .copied()
                    .unwrap_or(FollowerBind::NoOffer);
                let stored = app.with_app(|a| a.on_bind_result(&outcome));
                let event = match outcome {
                    FollowerBind::Bound { params, key } if stored == Some(true) => {
                        Some(LinkEvent::Bound {
                            bind_id: params.bind_id,
                            authenticated: key.is_some(),
                        })
                    }
                    FollowerBind::Refused(why) => Some(LinkEvent::BindRefused(why)),
                    _ => None,
                };
                (event, result.is_err())
            }
            None => (None, true),
        },
        LinkStep::Follow(params) => match chip.taulink() {
            Some(radio) => {
                // Keyed with the binding phrase's key when one is stored.
                let mut follower = match app.with_app(|a| a.follower(params, failsafe_us)) {
                    Some(follower) => follower,
                    None => return None,
                };
                let mut hooks = Hooks(app);
                let run = run_follower(radio, clock, &mut follower, &mut hooks);
                let ended = select(run, restart_due(app, ticker)).await;
                app.with_app(|a| a.on_link_down());
                (None, matches!(ended, Either::First(Err(_))))
            }
            None => (None, true),
        },
        LinkStep::BindOpenLrs { config, window_us } => {
            match chip.openlrs(config.version, config.band) {
                Some(radio) => {
                    let bind = openlrs_bind_window(radio, config, window_us);
                    let Either::First(result) = select(bind, keep_alive(app, ticker)).await;
                    let bound = result.as_ref().ok().copied().flatten();
                    let stored = app.with_app(|a| a.on_openlrs_bind_result(bound.as_ref()));
                    let event =
                        bound
                            .filter(|_| stored == Some(true))
                            .map(|d| LinkEvent::BoundOpenLrs {
                                rf_magic: d.rf_magic,
                            });
                    (event, result.is_err())
                }
                None => (None, true),
            }
        }
        LinkStep::FollowOpenLrs { config, data } => {
            match chip.openlrs(config.version, config.band) {
                Some(radio) => {
                    let mut rx = Receiver::new(config, Some(data));
                    let on_step = |now_us: u64, rx: &mut Receiver, events: &[_]| {
                        app.with_app(|a| a.on_openlrs_step(now_us, rx, events));
                    };
                    let run = run_openlrs_receiver(radio, &mut rx, on_step);
                    // The check-in races too: a slow profile's step (one hop cycle) outlasts
                    // the watchdog.
                    let waits = select(restart_due(app, ticker.clone()), keep_alive(app, ticker));
                    let ended = select(run, waits).await;
                    app.with_app(|a| a.on_link_down());
                    (None, matches!(ended, Either::First(_)))
                }
                None => (None, true),
            }
        }
    };
    if failed {
        idle(app, clock, RADIO_RETRY_US).await;
        return Some(LinkEvent::RadioFailed);
    }
    event
}
