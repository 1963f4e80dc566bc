//! The two link ends as tasks, the same for both worlds (packet-level mock radios or the
//! driver on virtual Si4432s): only the radio and clock types differ.

use telemetry::channels::FailsafeValues;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{bind_follower, run_follower};
use telemetry::link::master::{bind_master, run_master};
use telemetry::link::{Band, LinkClock, LinkParams, PacketRadio};

use crate::probe::{FlightApp, ModuleApp, Shared};
use crate::world::BIND_TIMEOUT_US;

/// The module (master) end: with `bind`, it offers the bind 0.3 s after boot first; then it
/// runs the master loop until the simulation ends.
pub(crate) async fn module_end<R: PacketRadio, C: LinkClock>(
    mut radio: R,
    mut clock: C,
    params: LinkParams,
    bind: bool,
    mut app: ModuleApp,
) {
    if bind {
        let start = clock.now_us() + 300_000;
        clock.sleep_until_us(start).await;
        let Ok(true) = bind_master(&mut radio, &mut clock, &params, BIND_TIMEOUT_US).await else {
            return;
        };
    }
    let mut master = Master::new(params);
    let _ = run_master(&mut radio, &mut clock, &mut master, &mut app).await;
}

/// How the flight end is started.
pub(crate) struct FlightStart {
    /// Listen for a bind first (else start bound with the given parameters).
    pub bind: bool,
    /// Parameters when already bound.
    pub params: LinkParams,
    /// Band to listen on for the bind.
    pub band: Band,
    /// Failsafe time, µs.
    pub failsafe_us: u64,
}

/// The flight (follower) end: binds (or boots a little later than the master, somewhere in
/// its hop cycle), records when it was bound on the shared virtual time (`virtual_us`), then
/// runs the follower loop.
pub(crate) async fn flight_end<R: PacketRadio, C: LinkClock>(
    mut radio: R,
    mut clock: C,
    start: FlightStart,
    mut app: FlightApp,
    record: Shared,
    virtual_us: impl Fn(&C) -> u64,
) {
    let params = if start.bind {
        match bind_follower(&mut radio, &mut clock, start.band, BIND_TIMEOUT_US).await {
            Ok(Some(p)) => p,
            _ => return,
        }
    } else {
        let boot = clock.now_us() + 123_457;
        clock.sleep_until_us(boot).await;
        start.params
    };
    record.borrow_mut().bound_us = Some(virtual_us(&clock));
    record.borrow_mut().follower_params = Some(params);
    let mut follower = Follower::new(params, FailsafeValues::default(), start.failsafe_us);
    let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut app).await;
}
