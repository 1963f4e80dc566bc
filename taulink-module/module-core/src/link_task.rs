//! The module's link task body, shared by the firmware and the simulator so neither writes
//! it twice: one [`run_link_step`] asks the core for its next session step
//! ([`App::next_link_step`], `crate::session`) and carries it out on the RFM22B
//! ([`DualRadio`]: TauLink's `LinkRadio`, or the chip lent to an OpenLRSng radio) — probe,
//! wait, the master or follower loop with the core as its hook, OpenLRSng's transmitter,
//! the binds — checking the task in every [`POLL_MS`] and asking the core
//! ([`App::poll_session`]) whether the running step must end; then it reports the outcome
//! (`App::on_*`) and hands the core's action to the board ([`LinkPorts::carry_out`]).
//!
//! The adapter only supplies the parts: [`LinkPorts`] (the core behind its lock, the
//! watchdog check-in, the millisecond clock, the action signals), the driver, the link's
//! clock and a hardware random number per step.

use core::convert::Infallible;

use ::openlrs::{BindData, BindingVersion, RfmType};
use embassy_futures::select::{Either, select};
use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;
use openlrs::dual::DualRadio;
use openlrs::radio::Clock;
use openlrs::roles::tx_bind;
use openlrs::tx::Transmitter;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{FollowerHooks, bind_follower, run_follower};
use telemetry::link::master::{MasterHooks, bind_master, run_master};
use telemetry::link::{FollowerAuth, LinkClock};

use crate::air::AirLink;
use crate::air::openlrs::run_openlrs_transmitter;
use crate::app::{Action, App};
use crate::ports::HandsetOutput;
use crate::session::{BindOutcome, LinkStep, POLL_MS, SessionEnd};

/// What the link task needs from its board.
pub trait LinkPorts {
    /// The handset side the core drives.
    type Handset: HandsetOutput;
    /// Runs `f` on the core (short, never awaits); `None` when it is not there.
    fn with_app<R>(&self, f: impl FnOnce(&mut App<AirLink, Self::Handset>) -> R) -> Option<R>;
    /// The link task is alive (the supervisor's radio bit).
    fn check_in(&self);
    /// Milliseconds since boot, wrapping (the session's clock).
    fn now_ms(&self) -> u32;
    /// Hands an action of the core to the task that carries it out (LED, save).
    fn carry_out(&self, action: Action);
}

/// What a step did worth logging.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkEvent {
    /// The radio failed during the step (the core probes it again next).
    RadioFailed,
}

/// The loops' hook into the core.
struct Hooks<'a, P>(&'a P);

impl<P: LinkPorts> MasterHooks for Hooks<'_, P> {
    fn on_slot(&mut self, now_us: u64, master: &mut Master) {
        let now_ms = self.0.now_ms();
        self.0
            .with_app(|app| app.on_master_slot(now_us, now_ms, master));
    }
}

impl<P: LinkPorts> FollowerHooks for Hooks<'_, P> {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        let now_ms = self.0.now_ms();
        self.0
            .with_app(|app| app.on_follower_step(now_us, now_ms, follower));
    }
}

/// Sleeps one [`POLL_MS`] on `clock`.
async fn poll_wait<K: LinkClock>(clock: &mut K) {
    let next = clock.now_us().saturating_add(u64::from(POLL_MS) * 1_000);
    clock.sleep_until_us(next).await;
}

/// Checks in every [`POLL_MS`] until the core ends the running step.
async fn poll_session<P: LinkPorts, K: LinkClock>(ports: &P, mut clock: K) -> SessionEnd {
    loop {
        ports.check_in();
        let now_ms = ports.now_ms();
        if let Some(end) = ports.with_app(|app| app.poll_session(now_ms)).flatten() {
            return end;
        }
        poll_wait(&mut clock).await;
    }
}

/// `step` to its end, checking in meanwhile.
async fn keep_alive<P: LinkPorts, K: LinkClock, T>(
    ports: &P,
    mut clock: K,
    step: impl Future<Output = T>,
) -> T {
    let ticking = async {
        loop {
            ports.check_in();
            poll_wait(&mut clock).await;
        }
    };
    match select(step, ticking).await {
        Either::First(value) => value,
        Either::Second(never) => never,
    }
}

/// A link loop until its radio fails or the core ends the step.
async fn run<P: LinkPorts, K: LinkClock, E>(
    ports: &P,
    clock: K,
    link: impl Future<Output = Result<Infallible, E>>,
) -> SessionEnd {
    match select(link, poll_session(ports, clock)).await {
        Either::First(Err(_)) => SessionEnd::RadioFailed,
        Either::First(Ok(never)) => match never {},
        Either::Second(end) => end,
    }
}

/// One step of the link task (see the module doc); the firmware and the simulator call it
/// in a loop, with a fresh hardware random number each time (`random`: the bind ID if a
/// master bind comes next).
pub async fn run_link_step<P, SPI, IRQ, SDN, D, C, K>(
    ports: &P,
    chip: &mut DualRadio<SPI, IRQ, SDN, D, C>,
    clock: &mut K,
    random: u32,
) -> Option<LinkEvent>
where
    P: LinkPorts,
    SPI: SpiDevice,
    IRQ: Wait,
    SDN: OutputPin,
    D: DelayNs,
    C: Clock,
    K: LinkClock + Clone,
{
    ports.check_in();
    let now_ms = ports.now_ms();
    let step = ports
        .with_app(|app| app.next_link_step(now_ms, random))
        .unwrap_or(LinkStep::Wait { ms: POLL_MS });
    let ticker = clock.clone();
    let (action, failed) = match step {
        LinkStep::Wait { ms } => {
            let mut sleeper = clock.clone();
            let until = sleeper.now_us().saturating_add(u64::from(ms) * 1_000);
            keep_alive(ports, ticker, sleeper.sleep_until_us(until)).await;
            (None, false)
        }
        LinkStep::WaitForBind => {
            let end = poll_session(ports, ticker).await;
            (ports.with_app(|app| app.on_session_end(end)), false)
        }
        LinkStep::RunOpenLrsTx(data) | LinkStep::BindOpenLrsTx { data, .. } => {
            openlrs_step(ports, chip, clock, step, data).await
        }
        _ => match chip.taulink() {
            None => (None, true),
            Some(radio) => match step {
                LinkStep::Probe => {
                    let present = radio.driver().reset().await.is_ok();
                    (
                        ports.with_app(|app| app.on_radio_present(present)),
                        !present,
                    )
                }
                // The core builds the loops: keyed with the binding phrase's key when set.
                LinkStep::RunMaster(params) => match ports.with_app(|app| app.master(params)) {
                    Some(mut master) => {
                        let mut hooks = Hooks(ports);
                        let link = run_master(radio, clock, &mut master, &mut hooks);
                        let end = run(ports, ticker, link).await;
                        let failed = end == SessionEnd::RadioFailed;
                        (ports.with_app(|app| app.on_session_end(end)), failed)
                    }
                    None => (None, false),
                },
                LinkStep::RunFollower {
                    params,
                    failsafe,
                    failsafe_us,
                } => match ports.with_app(|app| app.follower(params, failsafe, failsafe_us)) {
                    Some(mut follower) => {
                        let mut hooks = Hooks(ports);
                        let link = run_follower(radio, clock, &mut follower, &mut hooks);
                        let end = run(ports, ticker, link).await;
                        let failed = end == SessionEnd::RadioFailed;
                        (ports.with_app(|app| app.on_session_end(end)), failed)
                    }
                    None => (None, false),
                },
                LinkStep::BindMaster {
                    params,
                    auth,
                    key,
                    random,
                    timeout_us,
                } => {
                    let bind = bind_master(radio, clock, &params, &auth, &key, &random, timeout_us);
                    let result = keep_alive(ports, ticker, bind).await;
                    let failed = result.is_err();
                    let outcome = BindOutcome::offered(result);
                    (ports.with_app(|app| app.on_bind_outcome(outcome)), failed)
                }
                LinkStep::BindFollower {
                    band,
                    stored,
                    allow_plain,
                    random,
                    timeout_us,
                } => {
                    let auth = FollowerAuth {
                        phrase: None,
                        stored,
                        allow_plain,
                    };
                    let bind = bind_follower(radio, clock, band, &auth, &random, timeout_us);
                    let result = keep_alive(ports, ticker, bind).await;
                    let failed = result.is_err();
                    let outcome = BindOutcome::listened(result);
                    (ports.with_app(|app| app.on_bind_outcome(outcome)), failed)
                }
                _ => (None, false),
            },
        },
    };
    if let Some(action) = action.flatten() {
        ports.carry_out(action);
    }
    failed.then_some(LinkEvent::RadioFailed)
}

/// An OpenLRSng step: the transmitter loop or OpenLRSng's bind, on the chip lent to an
/// OpenLRSng radio for `data`'s generation and band.
async fn openlrs_step<P, SPI, IRQ, SDN, D, C, K>(
    ports: &P,
    chip: &mut DualRadio<SPI, IRQ, SDN, D, C>,
    clock: &K,
    step: LinkStep,
    data: BindData,
) -> (Option<Option<Action>>, bool)
where
    P: LinkPorts,
    SPI: SpiDevice,
    IRQ: Wait,
    SDN: OutputPin,
    D: DelayNs,
    C: Clock,
    K: LinkClock + Clone,
{
    let version = BindingVersion::from_byte(data.version).unwrap_or(BindingVersion::V39);
    let band = data.band().unwrap_or(RfmType::Mhz433);
    let Some(radio) = chip.openlrs(version, band) else {
        return (None, true);
    };
    if let LinkStep::BindOpenLrsTx { data, timeout_us } = step {
        let until = radio.now_us().saturating_add(timeout_us);
        let accepted = keep_alive(ports, clock.clone(), tx_bind(radio, &data, until)).await;
        let failed = accepted.is_err();
        let outcome = BindOutcome::openlrs(accepted);
        return (ports.with_app(|app| app.on_bind_outcome(outcome)), failed);
    }
    let end = match Transmitter::new(data, radio.now_us()) {
        Ok(tx) => {
            let mut tx = tx.with_stale_input_stop();
            let run = run_openlrs_transmitter(
                radio,
                &mut tx,
                |tx| {
                    ports.with_app(|app| app.on_openlrs_send(tx));
                },
                |now_us, tx, events| {
                    let now_ms = ports.now_ms();
                    ports.with_app(|app| app.on_openlrs_step(now_us, now_ms, tx, events));
                },
            );
            match select(run, poll_session(ports, clock.clone())).await {
                Either::First(_) => SessionEnd::RadioFailed,
                Either::Second(end) => end,
            }
        }
        Err(_) => poll_session(ports, clock.clone()).await,
    };
    let failed = end == SessionEnd::RadioFailed;
    (ports.with_app(|app| app.on_session_end(end)), failed)
}
