//! The follower's async loop: a thin shell that runs [`Follower`]'s steps on a radio and a
//! clock and lets the application take channel outputs and exchange telemetry at every
//! step.

use super::bind::{ACCEPT_REPEATS, BIND_KEY, LinkParams, bind_radio_config, offered_params};
use super::core::{Follower, Step};
use super::hopping::Band;
use super::radio::{LinkClock, LinkRx, PacketRadio};
use super::rate::FIFO_BYTES;
use super::recovery::Recovery;
use super::step_io::{receive_until, transmit_at, tune_until};
use crate::frame::{Frame, encode};

/// Gap between receiving an offer and answering, and between repeated accepts: the master
/// needs to turn around to RX (PLL settle) after its offer.
const ACCEPT_GAP_US: u64 = 2_000;

/// Bind mode on the follower (started by the bind button/command): listens on `band`'s bind
/// channel for an offer, answers with accepts and returns the offered parameters for the
/// caller to store, or `None` after `timeout_us`.
pub async fn bind_follower<R: PacketRadio, C: LinkClock>(
    radio: &mut R,
    clock: &mut C,
    band: Band,
    timeout_us: u64,
) -> Result<Option<LinkParams>, R::Error> {
    radio.configure(&bind_radio_config(band)).await?;
    radio.set_channel(0).await?;
    let give_up = clock.now_us() + timeout_us;
    let mut buf = [0u8; FIFO_BYTES];
    while clock.now_us() < give_up {
        let LinkRx::Packet { len, .. } = receive_until(radio, clock, &mut buf, give_up).await?
        else {
            continue;
        };
        let Some(params) = buf.get(..len).and_then(offered_params) else {
            continue;
        };
        let mut accept = [0u8; 16];
        let Ok(n) = encode(
            &Frame::BindAccept {
                bind_id: params.bind_id,
            },
            BIND_KEY,
            &mut accept,
        ) else {
            continue;
        };
        // An accept that cannot be built is no bind (never an empty frame on the air).
        let Some(accept) = accept.get(..n) else {
            continue;
        };
        for _ in 0..ACCEPT_REPEATS {
            clock.sleep_until_us(clock.now_us() + ACCEPT_GAP_US).await;
            radio.transmit(accept).await?;
        }
        return Ok(Some(params));
    }
    Ok(None)
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
    loop {
        let step = follower.plan(clock.now_us(), &mut buf);
        // Right after planning: a packet just received and any failsafe just declared are
        // visible to the application at once, not a step later.
        hooks.on_step(clock.now_us(), follower);
        let result = run_step(radio, clock, follower, step, &mut buf).await;
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
