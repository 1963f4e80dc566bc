//! The two link ends as tasks, the same for both worlds (packet-level mock radios or the
//! driver on virtual Si4432s): only the radio and clock types differ.

use telemetry::channels::FailsafeValues;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{bind_follower, run_follower};
use telemetry::link::master::{bind_master, run_master};
use telemetry::link::{Band, LinkClock, LinkKey, LinkParams, PacketRadio};

use crate::probe::{FlightApp, ModuleApp, Now, Shared};
use crate::scenario::Scenario;
use crate::world::BIND_TIMEOUT_US;

/// The two ends' applications for scenario `s`, both recording into `record`.
pub(crate) fn apps(s: &Scenario, now: Now, record: &Shared, salt: u64) -> (ModuleApp, FlightApp) {
    let module = ModuleApp::new(
        now.clone(),
        record.clone(),
        salt,
        s.telemetry_load,
        s.handset,
    );
    let flight = FlightApp::new(
        now,
        record.clone(),
        salt,
        s.telemetry_load,
        s.format,
        s.handset,
    );
    (module, flight)
}

/// The module (master) end: with `bind`, it offers the bind 0.3 s after boot first; then it
/// runs the master loop until the simulation ends.
pub(crate) async fn module_end<R: PacketRadio, C: LinkClock>(
    mut radio: R,
    mut clock: C,
    params: LinkParams,
    bind: bool,
    key: Option<(LinkKey, u64)>,
    mut app: ModuleApp,
) {
    if bind {
        let start = clock.now_us() + 300_000;
        clock.sleep_until_us(start).await;
        let Ok(true) = bind_master(&mut radio, &mut clock, &params, BIND_TIMEOUT_US).await else {
            return;
        };
    }
    let mut master = match key {
        Some((key, seed)) => Master::new(params).with_key(key).with_nonce_seed(seed),
        None => Master::new(params),
    };
    let _ = run_master(&mut radio, &mut clock, &mut master, &mut app).await;
}

/// The seed of the module's epoch nonces in a run of scenario `seed` (the module app seeds
/// them from its boot RNG; here from the scenario, unlike the follower's `seed ^ salt`).
pub(crate) fn master_nonce_seed(seed: u64, salt: u64) -> u64 {
    (seed ^ salt).rotate_left(32) ^ 0x6d61_7374_6572
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
    /// Link key (keyed link), and the seed of the follower's epoch nonces (a hardware RNG
    /// on the real controller).
    pub key: Option<(LinkKey, u64)>,
}

impl FlightStart {
    /// How scenario `s` starts the flight end: bound with `params`, or listening for a bind.
    pub(crate) fn of(s: &Scenario, bind: bool, params: LinkParams, salt: u64) -> Self {
        Self {
            bind,
            params,
            band: s.band,
            failsafe_us: s.failsafe_ms * 1000,
            key: s.key.map(|k| (k, s.seed ^ salt)),
        }
    }
}

/// The follower of `params`, keyed if `key` is given.
pub(crate) fn follower_for(
    params: LinkParams,
    failsafe_us: u64,
    key: Option<(LinkKey, u64)>,
) -> Follower {
    let follower = Follower::new(params, FailsafeValues::default(), failsafe_us);
    match key {
        Some((key, seed)) => follower.with_key(key).with_nonce_seed(seed),
        None => follower,
    }
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
    let mut follower = follower_for(params, start.failsafe_us, start.key);
    let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut app).await;
}
