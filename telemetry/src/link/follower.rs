//! The follower's async loop: a thin shell that runs [`Follower`]'s steps on a radio and a
//! clock and lets the application take channel outputs and exchange telemetry at every
//! step.

use super::auth::LinkKey;
use super::bind::{
    ACCEPT_REPEATS, Answering, BIND_KEY, BindRefusal, CONFIRM_WAIT_US, FollowerAuth, LinkParams,
    OfferNeeds, bind_radio_config, offer_needs, offered,
};
use super::core::{Follower, Step};
use super::hopping::Band;
use super::master::{ACCEPT_GAP_US, send_repeated};
use super::phrase::{Derivation, PhraseSecret};
use super::radio::{LinkClock, LinkRx, PacketRadio};
use super::rate::FIFO_BYTES;
use super::recovery::Recovery;
use super::step_io::{apply_power, receive_until, transmit_at, tune_until};
use crate::frame::{Frame, encode};

/// Iterations of the phrase's derivation between two yields to the executor (≈ 10 ms of a
/// 168 MHz Cortex-M4).
const DERIVATION_STEP: u32 = 64;

/// How a follower's bind window ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FollowerBind {
    /// Bound: the offered link and its key (`None`: an unauthenticated link), to store.
    Bound {
        /// The link.
        params: LinkParams,
        /// Its key.
        key: Option<LinkKey>,
    },
    /// An offer was heard but not bound, and why (the last such reason).
    Refused(BindRefusal),
    /// No offer within the window.
    NoOffer,
}

/// Bind mode on the follower (started by the owner's bind command): listens on `band`'s
/// bind channel, at the lowest power, for an offer it can take with `auth` (spec §12.1).
/// The first key-agreement offer it can take ends the window, bound or not — one guess per
/// window: it answers with its CPace share and confirmation (running the phrase's slow
/// derivation under the offer's salt first, yielding to the executor between steps), and
/// binds only on the master's confirmation, which carries the link's key. An
/// unauthenticated offer is taken only when `auth` allows it. `random`: 32 bytes of a
/// hardware RNG.
pub async fn bind_follower<R: PacketRadio, C: LinkClock>(
    radio: &mut R,
    clock: &mut C,
    band: Band,
    auth: &FollowerAuth<'_>,
    random: &[u8; 32],
    timeout_us: u64,
) -> Result<FollowerBind, R::Error> {
    radio.configure(&bind_radio_config(band)).await?;
    radio.set_channel(0).await?;
    let give_up = clock.now_us() + timeout_us;
    let mut buf = [0u8; FIFO_BYTES];
    let mut refused = None;
    while clock.now_us() < give_up {
        let LinkRx::Packet { len, .. } = receive_until(radio, clock, &mut buf, give_up).await?
        else {
            continue;
        };
        let Some(offer) = buf.get(..len).and_then(offered) else {
            continue;
        };
        let prs = match offer_needs(&offer, auth) {
            OfferNeeds::Refused(why) => {
                refused = Some(why);
                continue;
            }
            OfferNeeds::Plain => {
                let accept = Frame::BindAccept {
                    bind_id: offer.bind_id,
                    exchange: None,
                };
                send_repeated(radio, clock, &accept).await?;
                return Ok(FollowerBind::Bound {
                    params: LinkParams::from_offer(&offer),
                    key: None,
                });
            }
            OfferNeeds::Anonymous => None,
            OfferNeeds::Phrase {
                stored: Some(s), ..
            } => Some(s),
            OfferNeeds::Phrase { salt, stored: None } => {
                let Some(phrase) = auth.phrase else {
                    continue;
                };
                Some(derive(clock, phrase, salt).await)
            }
        };
        let prs: &[u8] = prs.as_ref().map_or(&[], |s| &s.prs);
        let Some(answering) = Answering::new(&offer, prs, random) else {
            continue;
        };
        return answer(radio, clock, &answering).await;
    }
    Ok(refused.map_or(FollowerBind::NoOffer, FollowerBind::Refused))
}

/// The phrase's derivation under `salt`, yielding to the executor every
/// [`DERIVATION_STEP`] iterations.
async fn derive<C: LinkClock>(clock: &mut C, phrase: &str, salt: [u8; 8]) -> PhraseSecret {
    let mut derivation = Derivation::new(phrase, salt);
    loop {
        if let Some(secret) = derivation.step(DERIVATION_STEP) {
            return secret;
        }
        clock.sleep_until_us(clock.now_us() + 1).await;
    }
}

/// Sends the accept and waits for the master's confirmation, answering a repeated offer
/// (its accept was lost) up to [`ACCEPT_REPEATS`] times in all.
async fn answer<R: PacketRadio, C: LinkClock>(
    radio: &mut R,
    clock: &mut C,
    answering: &Answering,
) -> Result<FollowerBind, R::Error> {
    let mut accept = [0u8; FIFO_BYTES];
    let Ok(n) = encode(&answering.accept(), BIND_KEY, &mut accept) else {
        return Ok(FollowerBind::Refused(BindRefusal::NotConfirmed));
    };
    let Some(accept) = accept.get(..n) else {
        return Ok(FollowerBind::Refused(BindRefusal::NotConfirmed));
    };
    let mut buf = [0u8; FIFO_BYTES];
    let mut sent = 0;
    let mut deadline = clock.now_us();
    loop {
        if sent < ACCEPT_REPEATS && clock.now_us() >= deadline {
            clock.sleep_until_us(clock.now_us() + ACCEPT_GAP_US).await;
            radio.transmit(accept).await?;
            sent += 1;
            deadline = clock.now_us() + CONFIRM_WAIT_US;
        }
        if clock.now_us() >= deadline {
            return Ok(FollowerBind::Refused(BindRefusal::NotConfirmed));
        }
        let LinkRx::Packet { len, .. } = receive_until(radio, clock, &mut buf, deadline).await?
        else {
            continue;
        };
        let packet = buf.get(..len).unwrap_or(&[]);
        match answering.on_confirm(packet) {
            Some(Some(key)) => {
                return Ok(FollowerBind::Bound {
                    params: answering.params(),
                    key: Some(key),
                });
            }
            Some(None) => return Ok(FollowerBind::Refused(BindRefusal::NotConfirmed)),
            None if answering.is_repeat(packet) => deadline = clock.now_us(),
            None => {}
        }
    }
}

/// The application side of a follower: called after every plan, before the step runs.
pub trait FollowerHooks {
    /// Read channel outputs and telemetry from `follower`, feed telemetry in.
    fn on_step(&mut self, now_us: u64, follower: &mut Follower);
}

/// Runs the follower forever. Radio errors are ridden through: after each the radio is
/// re-configured ([`PacketRadio::recover`]) and the session goes on (counted in
/// `follower.counters().radio_errors`); only [`MAX_CONSECUTIVE_RADIO_ERRORS`](super::core::MAX_CONSECUTIVE_RADIO_ERRORS) errors in a row
/// end it with the last error. The radio's health is checked every
/// [`HEALTH_CHECK_PERIOD_US`](super::core::HEALTH_CHECK_PERIOD_US). Failsafe follows from the silence as always.
pub async fn run_follower<R: PacketRadio, C: LinkClock, H: FollowerHooks>(
    radio: &mut R,
    clock: &mut C,
    follower: &mut Follower,
    hooks: &mut H,
) -> Result<core::convert::Infallible, R::Error> {
    let config = follower.radio_config();
    radio.configure(&config).await?;
    let mut buf = [0u8; FIFO_BYTES];
    let mut recovery = Recovery::new(clock.now_us());
    let mut power = None;
    loop {
        let step = follower.plan(clock.now_us(), &mut buf);
        // Right after planning: a packet just received and any failsafe just declared are
        // visible to the application at once, not a step later.
        hooks.on_step(clock.now_us(), follower);
        let result = run_step(radio, clock, follower, step, &mut buf).await;
        // The power the hooks asked for, between steps (never inside a planned packet).
        let result = match result {
            Ok(()) => apply_power(radio, follower.tx_power(), &mut power).await,
            failed => failed,
        };
        recovery
            .after_step(radio, clock, &config, result, || follower.on_radio_error())
            .await?;
    }
}

/// Carries out one planned step; on an error the follower has been moved past it.
async fn run_step<R: PacketRadio, C: LinkClock>(
    radio: &mut R,
    clock: &mut C,
    follower: &mut Follower,
    step: Step,
    buf: &mut [u8; FIFO_BYTES],
) -> Result<(), R::Error> {
    match step {
        Step::Transmit {
            channel,
            at_us,
            len,
        } => {
            let frame = buf.get(..len).unwrap_or(&[]);
            transmit_at(radio, clock, follower, (channel, at_us, frame), false).await?;
        }
        Step::Listen {
            channel,
            from_us,
            until_us,
        } => {
            // A failed listen needs no bookkeeping: the next plan counts its slot as missed.
            tune_until(radio, clock, channel, from_us).await?;
            let outcome = receive_until(radio, clock, buf, until_us).await?;
            follower.on_received(outcome, buf, clock.now_us());
        }
        Step::Idle => follower.on_skipped(),
    }
    Ok(())
}
