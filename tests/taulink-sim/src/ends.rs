//! The two link ends as tasks, the same for both worlds (packet-level mock radios or the
//! driver on virtual Si4432s): only the radio and clock types differ.

use telemetry::channels::FailsafeValues;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{FollowerBind, bind_follower, run_follower};
use telemetry::link::master::{MasterBind, bind_master, run_master};
use telemetry::link::{
    Band, BindAuth, FollowerAuth, LinkClock, LinkKey, LinkParams, PacketRadio, PhraseSecret,
};

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

/// How the module binds in a run: the key agreement (CPace on the phrase's derivation, or
/// without a phrase, or none for an unkeyed link) and its randomness.
pub(crate) struct ModuleBind {
    /// The key agreement.
    pub auth: BindAuth,
    /// 32 bytes of the module's RNG.
    pub random: [u8; 32],
}

impl ModuleBind {
    /// The bind of scenario `s` (its phrase under a salt of the run, its key).
    pub(crate) fn of(s: &Scenario, salt: u64) -> Self {
        let salt8 = crate::scenario::seed_bytes(s.seed, salt ^ 0x5a17);
        let auth = match (&s.phrase, s.key) {
            (_, None) => BindAuth::Plain,
            (None, Some(_)) => BindAuth::Anonymous,
            (Some(p), Some(_)) => {
                BindAuth::Phrase(PhraseSecret::derive(p, crate::scenario::head(&salt8)))
            }
        };
        Self {
            auth,
            random: crate::scenario::seed_bytes(s.seed, salt ^ 0xb1d),
        }
    }
}

/// The module (master) end: with `bind`, it offers the bind 0.3 s after boot first (handing
/// over the run's key, if keyed); then it runs the master loop until the simulation ends.
pub(crate) async fn module_end<R: PacketRadio, C: LinkClock>(
    mut radio: R,
    mut clock: C,
    params: LinkParams,
    bind: Option<ModuleBind>,
    key: Option<(LinkKey, u64)>,
    mut app: ModuleApp,
) {
    if let Some(bind) = bind {
        let start = clock.now_us() + 300_000;
        clock.sleep_until_us(start).await;
        let handed = key.map_or(LinkKey::from_bytes([0; 16]), |(k, _)| k);
        let result = bind_master(
            &mut radio,
            &mut clock,
            &params,
            &bind.auth,
            &handed,
            &bind.random,
            BIND_TIMEOUT_US,
        )
        .await;
        let Ok(MasterBind::Bound(_)) = result else {
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
    /// The phrase typed for the bind window.
    pub phrase: Option<String>,
    /// The bind's randomness.
    pub random: [u8; 32],
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
            phrase: s.phrase.clone(),
            random: crate::scenario::seed_bytes(s.seed, salt ^ 0xf011),
        }
    }

    /// What the bind window takes: the phrase, and an unkeyed run's unauthenticated link.
    pub(crate) fn auth(&self) -> FollowerAuth<'_> {
        FollowerAuth {
            phrase: self.phrase.as_deref(),
            stored: None,
            allow_plain: self.key.is_none(),
        }
    }

    /// The bind window: the link and its key, if one was bound.
    pub(crate) async fn bind<R: PacketRadio, C: LinkClock>(
        &self,
        radio: &mut R,
        clock: &mut C,
    ) -> Option<(LinkParams, Option<LinkKey>)> {
        let auth = self.auth();
        match bind_follower(
            radio,
            clock,
            self.band,
            &auth,
            &self.random,
            BIND_TIMEOUT_US,
        )
        .await
        {
            Ok(FollowerBind::Bound { params, key }) => Some((params, key)),
            _ => None,
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
    let (params, key) = if start.bind {
        match start.bind(&mut radio, &mut clock).await {
            Some((params, key)) => (params, key.zip(start.key.map(|(_, seed)| seed))),
            None => return,
        }
    } else {
        let boot = clock.now_us() + 123_457;
        clock.sleep_until_us(boot).await;
        (start.params, start.key)
    };
    record.borrow_mut().bound_us = Some(virtual_us(&clock));
    record.borrow_mut().follower_params = Some(params);
    let mut follower = follower_for(params, start.failsafe_us, key);
    let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut app).await;
}
