//! The link task's decisions: when to probe the radio, which link loop to run with which
//! parameters (master in the transmitter role, follower in the receiver role), when a running
//! loop must stop (a bind request, a radio failure, a hook gone silent) and how to bind in
//! each role. The firmware's link task only asks "what next?" ([`crate::app::App::next_link_step`]),
//! carries the step out on the radio and feeds the outcome back (`App::on_*`).

use telemetry::channels::{Failsafe, FailsafeValues, MAX_CHANNELS};
use telemetry::link::core::follower::DEFAULT_FAILSAFE_US;
use telemetry::link::follower::FollowerBind;
use telemetry::link::master::MasterBind;
use telemetry::link::{Band, BindAuth, Entropy, LinkKey, LinkParams, PhraseSecret};

use ::openlrs::BindData;

use crate::air::{link_params, new_bind_params};
use crate::settings::{Role, Settings, openlrs};

/// How long one bind attempt lasts.
pub const BIND_TIMEOUT_US: u64 = 10_000_000;
/// A running link loop counts as alive while its hook ran within this time. Longer than any
/// one step (the follower's acquisition dwell is one hop cycle, ≤ 660 ms), short enough that
/// a hung radio is noticed.
pub const HOOK_SILENCE_MS: u32 = 2_000;
/// With no radio found, probe again after this long.
pub const PROBE_RETRY_MS: u32 = 1_000;
/// How often the task should call [`crate::app::App::poll_session`] while a step runs.
pub const POLL_MS: u32 = 50;

/// What the link task does next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkStep {
    /// Reset and probe the radio; report with `App::on_radio_present`.
    Probe,
    /// No radio: wait this long (checking in), then ask again.
    Wait {
        /// Milliseconds to wait.
        ms: u32,
    },
    /// Unbound: idle until [`crate::app::App::poll_session`] says a bind was asked for.
    WaitForBind,
    /// Run the master loop (transmitter role), the core's `on_master_slot` as its hook.
    RunMaster(LinkParams),
    /// Run the follower loop (receiver role), the core's `on_follower_step` as its hook.
    RunFollower {
        /// The bound link.
        params: LinkParams,
        /// Every channel held: the PPM output applies the module's own failsafe setting
        /// once the follower reports failsafe.
        failsafe: FailsafeValues,
        /// The follower's silence timeout.
        failsafe_us: u64,
    },
    /// Offer `params` (a fresh bind ID) until a follower accepts or the timeout passes,
    /// agreeing a key as `auth` says and handing over `key`, the link's key
    /// (`telemetry::link::master::bind_master`).
    BindMaster {
        /// What is offered.
        params: LinkParams,
        /// How the key is agreed.
        auth: BindAuth,
        /// The link's key to hand over (the module's key for this link).
        key: LinkKey,
        /// The CPace randomness.
        random: [u8; 32],
        /// How long to offer.
        timeout_us: u64,
    },
    /// Run the OpenLRSng transmitter (`settings.protocol` OpenLRSng) on this bind data,
    /// `crate::air::openlrs::run_openlrs_transmitter` with the core's `on_openlrs_*` hooks.
    RunOpenLrsTx(BindData),
    /// OpenLRSng's bind procedure: send `data`'s bind packet (every 200 ms, at the bind
    /// power, `openlrs::roles::tx_bind`) until a receiver answers or the
    /// timeout passes; report with `App::on_bind_outcome(BindOutcome::Offered { .. })`.
    BindOpenLrsTx {
        /// The bind data offered (with the hop seed the bind gives the link).
        data: BindData,
        /// How long to offer.
        timeout_us: u64,
    },
    /// Listen for a master's offer on `band` (`telemetry::link::follower::bind_follower`),
    /// with the stored phrase derivation (taken when the master's salt is this module's) and
    /// the unauthenticated setting.
    BindFollower {
        /// The band's bind channel.
        band: Band,
        /// The stored phrase derivation.
        stored: Option<PhraseSecret>,
        /// Whether an unauthenticated link may be bound.
        allow_plain: bool,
        /// The CPace randomness.
        random: [u8; 32],
        /// How long to listen.
        timeout_us: u64,
    },
}

/// Why a running step ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SessionEnd {
    /// A long press asked for a bind: bind next.
    BindRequested,
    /// The radio driver failed: probe it again.
    RadioFailed,
    /// The loop's hook stopped running for [`HOOK_SILENCE_MS`]: probe the radio again.
    HookSilent,
    /// A setting the running link uses changed (from the radio's device tool): start again
    /// with the new link parameters.
    SettingsChanged,
}

/// How a bind step ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BindOutcome {
    /// Master: how the offer ended.
    Offered(MasterBind),
    /// Follower: what the window brought.
    Listened(FollowerBind),
    /// OpenLRSng: whether a receiver took the bind data.
    OpenLrs {
        /// Accepted within the timeout.
        accepted: bool,
    },
    /// The radio failed during the bind.
    RadioFailed,
}

impl BindOutcome {
    /// The master's bind result (`telemetry::link::master::bind_master`).
    pub fn offered<E>(result: Result<MasterBind, E>) -> Self {
        result.map_or(Self::RadioFailed, Self::Offered)
    }

    /// The follower's bind result (`telemetry::link::follower::bind_follower`).
    pub fn listened<E>(result: Result<FollowerBind, E>) -> Self {
        result.map_or(Self::RadioFailed, Self::Listened)
    }

    /// OpenLRSng's bind result (`openlrs::roles::tx_bind`).
    pub fn openlrs<E>(result: Result<bool, E>) -> Self {
        result.map_or(Self::RadioFailed, |accepted| Self::OpenLrs { accepted })
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Probe,
    Absent,
    Ready,
    WaitingForBind,
    Running,
    Bind,
    Binding,
}

/// What a master bind offered: the link on air (the model's identity under model match)
/// and what the module stores if it is accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Offer {
    /// The parameters offered on air (what the receiver stores).
    pub params: LinkParams,
    /// The module's own bind ID to store (before any model mix).
    pub bind_id: u32,
    /// The module's key to store (each link's key derives from it; `None` for an
    /// unauthenticated bind).
    pub module_key: Option<LinkKey>,
    /// The radio model the offer was made under (model match on), to record as bound.
    pub model: Option<u8>,
}

/// The first 16 of 32 random bytes.
fn first16(bytes: [u8; 32]) -> [u8; 16] {
    core::array::from_fn(|i| bytes.get(i).copied().unwrap_or(0))
}

/// The link of `params` for `model` (model match on and a model selected), else `params`.
fn with_model(params: LinkParams, model: Option<u8>) -> LinkParams {
    model.map_or(params, |m| params.for_model(m))
}

/// The link task's state machine (held by the core's `App`).
#[derive(Debug, Clone)]
pub struct Session {
    state: State,
    last_hook_ms: u32,
    offered: Option<Offer>,
    offered_seed: Option<u32>,
}

impl Default for Session {
    fn default() -> Self {
        Self::new()
    }
}

impl Session {
    /// Before the first probe.
    pub const fn new() -> Self {
        Self {
            state: State::Probe,
            last_hook_ms: 0,
            offered: None,
            offered_seed: None,
        }
    }

    /// The probe's result.
    pub fn on_probe(&mut self, present: bool) {
        self.state = if present { State::Ready } else { State::Absent };
    }

    /// The next step for `settings`, at `now_ms`; `model` is the radio model the link's
    /// identity is mixed with (model match on and a model selected, else `None`); `random`
    /// gives a new bind ID when a master bind is next — except under a model, where a bound
    /// module keeps its ID (and its key) so the receivers bound under other models still
    /// fly; `entropy` the bind's secrets (a new module key, the CPace randomness). A step
    /// still running when this is called is abandoned: probe again.
    pub fn next(
        &mut self,
        settings: &Settings,
        model: Option<u8>,
        now_ms: u32,
        random: u32,
        entropy: &mut Entropy,
    ) -> LinkStep {
        match self.state {
            State::Absent => {
                self.state = State::Probe;
                LinkStep::Wait { ms: PROBE_RETRY_MS }
            }
            State::Ready if settings.protocol.openlrs_version().is_some() => {
                match openlrs::bind_data(settings) {
                    Ok(data) => {
                        self.state = State::Running;
                        self.last_hook_ms = now_ms;
                        LinkStep::RunOpenLrsTx(data)
                    }
                    // Settings that make no OpenLRSng link (only a damaged record can hold
                    // them): nothing goes on air until they change.
                    Err(_) => {
                        self.state = State::WaitingForBind;
                        LinkStep::WaitForBind
                    }
                }
            }
            State::Ready => match link_params(settings) {
                None => {
                    self.state = State::WaitingForBind;
                    LinkStep::WaitForBind
                }
                Some(params) => {
                    self.state = State::Running;
                    self.last_hook_ms = now_ms;
                    match settings.role {
                        Role::Transmitter => LinkStep::RunMaster(with_model(params, model)),
                        Role::Receiver => LinkStep::RunFollower {
                            params,
                            failsafe: FailsafeValues([Failsafe::Hold; MAX_CHANNELS]),
                            failsafe_us: DEFAULT_FAILSAFE_US,
                        },
                    }
                }
            },
            State::Bind if settings.protocol.openlrs_version().is_some() => {
                // The first bind gives the link its own magic and hop channels: OpenLRSng's
                // factory ones are every unbound transmitter's.
                let seed = match settings.openlrs.hop_seed {
                    0 => random.max(1),
                    seed => seed,
                };
                let mut with_seed = *settings;
                with_seed.openlrs.hop_seed = seed;
                match openlrs::bind_data(&with_seed) {
                    Ok(data) => {
                        self.state = State::Binding;
                        self.offered_seed = Some(seed);
                        LinkStep::BindOpenLrsTx {
                            data,
                            timeout_us: BIND_TIMEOUT_US,
                        }
                    }
                    Err(_) => {
                        self.state = State::WaitingForBind;
                        LinkStep::WaitForBind
                    }
                }
            }
            State::Bind => {
                self.state = State::Binding;
                match settings.role {
                    Role::Transmitter => {
                        let (base, module_key) = match (model, link_params(settings)) {
                            (Some(_), Some(bound)) => (bound, settings.link_key),
                            _ => (new_bind_params(settings, random), None),
                        };
                        // A new link gets a new module key; a model's link keeps the key.
                        let module_key = module_key.unwrap_or_else(|| {
                            LinkKey::from_bytes(first16(entropy.draw(b"module key")))
                        });
                        let params = with_model(base, model);
                        let auth = match (settings.plain, settings.phrase()) {
                            (true, _) => BindAuth::Plain,
                            (false, Some(secret)) => BindAuth::Phrase(secret),
                            (false, None) => BindAuth::Anonymous,
                        };
                        self.offered = Some(Offer {
                            params,
                            bind_id: base.bind_id,
                            module_key: (!settings.plain).then_some(module_key),
                            model,
                        });
                        LinkStep::BindMaster {
                            params,
                            auth,
                            key: module_key.for_link(params.bind_id),
                            random: entropy.draw(b"bind"),
                            timeout_us: BIND_TIMEOUT_US,
                        }
                    }
                    Role::Receiver => LinkStep::BindFollower {
                        band: settings.band,
                        stored: settings.phrase(),
                        allow_plain: settings.plain,
                        random: entropy.draw(b"bind"),
                        timeout_us: BIND_TIMEOUT_US,
                    },
                }
            }
            State::Probe | State::WaitingForBind | State::Running | State::Binding => {
                self.state = State::Probe;
                LinkStep::Probe
            }
        }
    }

    /// Whether a link step (or the unbound wait) is running and would have to end for new
    /// settings to take effect.
    pub fn running(&self) -> bool {
        matches!(self.state, State::Running | State::WaitingForBind)
    }

    /// The running loop's hook ran at `now_ms`.
    pub fn on_hook(&mut self, now_ms: u32) {
        self.last_hook_ms = now_ms;
    }

    /// Whether the running step must stop, at `now_ms`; `bind_requested` is a pending long
    /// press (only consumed when this returns [`SessionEnd::BindRequested`]).
    pub fn poll(&self, now_ms: u32, bind_requested: bool) -> Option<SessionEnd> {
        match self.state {
            State::Running | State::WaitingForBind if bind_requested => {
                Some(SessionEnd::BindRequested)
            }
            State::Running if now_ms.wrapping_sub(self.last_hook_ms) > HOOK_SILENCE_MS => {
                Some(SessionEnd::HookSilent)
            }
            _ => None,
        }
    }

    /// The running step ended.
    pub fn on_end(&mut self, end: SessionEnd) {
        self.state = match end {
            SessionEnd::BindRequested => State::Bind,
            SessionEnd::RadioFailed | SessionEnd::HookSilent | SessionEnd::SettingsChanged => {
                State::Probe
            }
        };
    }

    /// A bind step ended: the radio is probed again either way. Returns what this end
    /// offered (master role).
    pub fn on_bind_done(&mut self) -> Option<Offer> {
        self.state = State::Probe;
        self.offered.take()
    }

    /// The hop seed the last OpenLRSng bind offered (taken once, after `on_bind_done`).
    pub fn take_offered_seed(&mut self) -> Option<u32> {
        self.offered_seed.take()
    }
}

#[cfg(test)]
#[path = "session_tests.rs"]
mod tests;
