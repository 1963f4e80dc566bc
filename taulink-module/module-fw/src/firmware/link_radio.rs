//! The link loop's embassy plumbing for the link task: embassy-time as the link's
//! `LinkClock`, the loops' hook into the module core, and the wrappers that keep the task
//! checked in while a link step runs (the driver adapter is `radio_rfm22b::link::LinkRadio`).

use core::convert::Infallible;

use embassy_futures::select::{Either, select};
use embassy_time::{Instant, Timer};
use module_core::session::{POLL_MS, SessionEnd};
use telemetry::link::LinkClock;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::FollowerHooks;
use telemetry::link::master::MasterHooks;

use crate::firmware::shared::{now_ms, with_app};
use crate::firmware::tasks::supervisor::{Watched, check_in};

/// embassy-time in µs: the same clock the JR-line task stamps CRSF frames with, so the
/// link's slot times are directly the CRSF timing frame's phase.
pub struct EmbassyClock;

impl LinkClock for EmbassyClock {
    fn now_us(&self) -> u64 {
        Instant::now().as_micros()
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        Timer::at(Instant::from_micros(deadline_us)).await;
    }
}

/// The loops' hook: the module core exchanges channels, records and statistics.
pub struct Hooks;

impl MasterHooks for Hooks {
    fn on_slot(&mut self, now_us: u64, master: &mut Master) {
        with_app(|app| app.on_master_slot(now_us, now_ms(), master));
    }
}

impl FollowerHooks for Hooks {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        with_app(|app| app.on_follower_step(now_us, now_ms(), follower));
    }
}

/// Checks in every `POLL_MS` until the core ends the running step.
pub async fn poll_session() -> SessionEnd {
    loop {
        check_in(Watched::Radio);
        if let Some(end) = with_app(|app| app.poll_session(now_ms())).flatten() {
            return end;
        }
        Timer::after_millis(POLL_MS.into()).await;
    }
}

/// `step` to its end, checking in meanwhile.
pub async fn keep_alive<T>(step: impl Future<Output = T>) -> T {
    let ticking = async {
        loop {
            check_in(Watched::Radio);
            Timer::after_millis(POLL_MS.into()).await;
        }
    };
    match select(step, ticking).await {
        Either::First(value) => value,
        Either::Second(never) => never,
    }
}

/// A link loop until its radio fails or the core ends the step.
pub async fn run<E: defmt::Format>(
    link: impl Future<Output = Result<Infallible, E>>,
) -> SessionEnd {
    match select(link, poll_session()).await {
        Either::First(Err(e)) => {
            log(&e);
            SessionEnd::RadioFailed
        }
        Either::First(Ok(never)) => match never {},
        Either::Second(end) => end,
    }
}

/// A radio error, logged.
pub fn log<E: defmt::Format>(error: &E) {
    defmt::warn!("link radio: {}", error);
}
