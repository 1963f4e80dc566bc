//! The master's async loop: a thin shell that runs [`Master`]'s steps on a radio and a clock,
//! one slot after another on its own time base, and lets the application exchange channels
//! and telemetry with the state machine at every slot boundary.

use super::auth::LinkKey;
use super::bind::{
    ACCEPT_REPEATS, Accepted, BIND_KEY, BindAuth, LinkParams, OFFER_PERIOD_US, Offering,
    bind_radio_config,
};
use super::core::{Master, Step};
use super::radio::{LinkClock, LinkRx, PacketRadio};
use super::rate::{FIFO_BYTES, PLL_SETTLE_US, RateMode};
use super::recovery::Recovery;
use super::schedule::SlotKind;
use super::step_io::{apply_power, receive_until, transmit_at, tune_until};
use crate::frame::{Frame, encode};

/// Gap before each bind answer or confirmation: the peer needs to turn around to RX (PLL
/// settle) after its own frame.
pub(super) const ACCEPT_GAP_US: u64 = 2_000;

/// How a master's bind ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MasterBind {
    /// A follower took the offer: the link's key it now holds (`None`: unauthenticated).
    Bound(Option<LinkKey>),
    /// A follower answered but its key confirmation was wrong: the phrases differ (or
    /// another radio guessed). The bind ends: one guess per bind.
    Mismatch,
    /// Nobody answered before the timeout.
    NoAnswer,
}

/// Bind mode on the master (started by the bind button/command): offers `params` on the
/// band's bind channel, at the lowest power, every [`OFFER_PERIOD_US`] and listens in
/// between, agreeing a key as `auth` says (spec §12.1: CPace on the phrase's derivation, or
/// without a phrase, or none), until a follower accepts or `timeout_us` passes. A key
/// agreement hands over `key` (the link's key the module chose), sealed under the agreed
/// session key, in the confirmation it then sends [`ACCEPT_REPEATS`] times. `random`: 32
/// bytes of a hardware RNG (the CPace scalar and session).
pub async fn bind_master<R: PacketRadio, C: LinkClock>(
    radio: &mut R,
    clock: &mut C,
    params: &LinkParams,
    auth: &BindAuth,
    key: &LinkKey,
    random: &[u8; 32],
    timeout_us: u64,
) -> Result<MasterBind, R::Error> {
    radio.configure(&bind_radio_config(params.band)).await?;
    radio.set_channel(0).await?;
    let give_up = clock.now_us() + timeout_us;
    let offering = Offering::new(params, auth, random);
    let mut offer = [0u8; FIFO_BYTES];
    let Ok(offer_len) = encode(&Frame::BindOffer(offering.offer()), BIND_KEY, &mut offer) else {
        return Ok(MasterBind::NoAnswer);
    };
    // An offer that cannot be built is no bind (never an empty frame on the air).
    let Some(offer) = offer.get(..offer_len) else {
        return Ok(MasterBind::NoAnswer);
    };
    let mut buf = [0u8; FIFO_BYTES];
    while clock.now_us() < give_up {
        let period_end = clock.now_us() + u64::from(OFFER_PERIOD_US);
        radio.transmit(offer).await?;
        while clock.now_us() < period_end {
            let LinkRx::Packet { len, .. } =
                receive_until(radio, clock, &mut buf, period_end).await?
            else {
                continue;
            };
            match buf.get(..len).and_then(|p| offering.on_accept(p, key)) {
                Some(Accepted::Bound { key, confirm }) => {
                    if let Some(confirm) = confirm {
                        send_repeated(radio, clock, &confirm).await?;
                    }
                    return Ok(MasterBind::Bound(key));
                }
                Some(Accepted::Mismatch) => return Ok(MasterBind::Mismatch),
                None => {}
            }
        }
    }
    Ok(MasterBind::NoAnswer)
}

/// Sends `frame` [`ACCEPT_REPEATS`] times, [`ACCEPT_GAP_US`] apart (the peer needs to turn
/// around to RX after its own frame).
pub(super) async fn send_repeated<R: PacketRadio, C: LinkClock>(
    radio: &mut R,
    clock: &mut C,
    frame: &Frame<'_>,
) -> Result<(), R::Error> {
    let mut bytes = [0u8; FIFO_BYTES];
    let Ok(n) = encode(frame, BIND_KEY, &mut bytes) else {
        return Ok(());
    };
    let Some(bytes) = bytes.get(..n) else {
        return Ok(());
    };
    for _ in 0..ACCEPT_REPEATS {
        clock.sleep_until_us(clock.now_us() + ACCEPT_GAP_US).await;
        radio.transmit(bytes).await?;
    }
    Ok(())
}

/// When, after its slot start, an uplink's channels are latched: once the transmitter is on
/// and its PLL has settled (TX lead + SPI set-up + PLL settle, the packet's start in the slot
/// budget). The radio was started with the frame's length ([`Master::uplink_len`],
/// [`PacketRadio::begin_transmit`]); while the chip sends preamble and sync (≥ 250 µs at
/// 256 kbps, more at the slower rates) the master builds the frame and loads the FIFO
/// ([`PacketRadio::finish_transmit`]). Latched here, the channels reach the air 306 µs (F700)
/// later than when they were latched before the SPI set-up and the PLL settle.
pub fn uplink_latch_offset_us(rate: RateMode) -> u32 {
    rate.tx_lead_us() + rate.tx_setup_us() + PLL_SETTLE_US
}

/// The application side of a master: called once per slot — at the start of a downlink slot,
/// and at [`uplink_latch_offset_us`] into an uplink slot (the transmitter on, preamble on
/// the air), so the channels it sets are as fresh as the slot allows.
pub trait MasterHooks {
    /// Feed channels and telemetry into `master`, read telemetry and stats out.
    fn on_slot(&mut self, now_us: u64, master: &mut Master);
}

/// Runs the master forever. Radio errors are ridden through as in
/// [`run_follower`](super::follower::run_follower): the radio is re-configured and the slot
/// grid goes on (counted in `master.counters().radio_errors`); only
/// [`MAX_CONSECUTIVE_RADIO_ERRORS`](super::core::MAX_CONSECUTIVE_RADIO_ERRORS) errors in a row end the session. The radio's health is
/// checked every [`HEALTH_CHECK_PERIOD_US`](super::core::HEALTH_CHECK_PERIOD_US).
pub async fn run_master<R: PacketRadio, C: LinkClock, H: MasterHooks>(
    radio: &mut R,
    clock: &mut C,
    master: &mut Master,
    hooks: &mut H,
) -> Result<core::convert::Infallible, R::Error> {
    let config = master.radio_config();
    radio.configure(&config).await?;
    let slot_us = u64::from(master.schedule().slot_us());
    let mut slot_start_us = clock.now_us();
    let mut buf = [0u8; FIFO_BYTES];
    let mut recovery = Recovery::new(clock.now_us());
    let mut power = None;
    loop {
        // Fell behind by a whole slot (a debugger, a radio reset): skip, keep the grid.
        while clock.now_us() > slot_start_us + slot_us / 2 {
            master.on_skipped();
            slot_start_us += slot_us;
        }
        // Channels are latched once the uplink's transmitter is on, not at the slot start:
        // every uplink then carries the freshest handset input the slot allows.
        let result = if master.schedule().kind(master.slot()) == SlotKind::Uplink {
            run_uplink(radio, clock, master, hooks, slot_start_us, &mut buf).await
        } else {
            hooks.on_slot(slot_start_us, master);
            let step = master.plan(slot_start_us, &mut buf);
            run_slot(radio, clock, master, step, &mut buf).await
        };
        // The power the hooks asked for, after the slot's packet and before the next.
        let result = match result {
            Ok(()) => apply_power(radio, master.tx_power(), &mut power).await,
            failed => failed,
        };
        recovery
            .after_step(radio, clock, &config, result, || master.on_radio_error())
            .await?;
        slot_start_us += slot_us;
        clock.sleep_until_us(slot_start_us).await;
    }
}

/// An uplink slot: the radio is started with the frame's length at the TX lead, the
/// channels are latched and the frame built once its PLL has settled
/// ([`uplink_latch_offset_us`]), and the bytes follow into the FIFO while preamble and sync
/// are on the air. On an error the master has been moved past the slot.
async fn run_uplink<R: PacketRadio, C: LinkClock, H: MasterHooks>(
    radio: &mut R,
    clock: &mut C,
    master: &mut Master,
    hooks: &mut H,
    slot_start_us: u64,
    buf: &mut [u8; FIFO_BYTES],
) -> Result<(), R::Error> {
    let rate = master.schedule().rate;
    let at_us = slot_start_us + u64::from(rate.tx_lead_us());
    let (Some(len), channel) = (master.uplink_len(), master.channel()) else {
        hooks.on_slot(slot_start_us, master);
        master.on_skipped();
        return Ok(());
    };
    let started = async {
        radio.set_channel(channel).await?;
        // Too late for this slot (e.g. right after a radio recovery): an uplink off the
        // grid would drag the follower's grid with it, so the slot is skipped.
        if clock.now_us() > at_us {
            return Ok(false);
        }
        clock.sleep_until_us(at_us).await;
        radio.begin_transmit(len).await?;
        Ok(true)
    }
    .await;
    match started {
        Ok(true) => {}
        Ok(false) => {
            hooks.on_slot(slot_start_us, master);
            master.on_skipped();
            return Ok(());
        }
        Err(e) => {
            master.on_skipped();
            return Err(e);
        }
    }
    clock
        .sleep_until_us(slot_start_us + u64::from(uplink_latch_offset_us(rate)))
        .await;
    hooks.on_slot(slot_start_us, master);
    // Built once, with the fresh channels and the length counted above (stream data
    // capped). Were it ever another length, nothing is loaded: the chip then sends a packet
    // that fails its CRC (a FIFO underflow) — a lost uplink, never a wrong one.
    let frame = match master.plan(slot_start_us, buf) {
        Step::Transmit { len: built, .. } if built == len => buf.get(..len),
        _ => None,
    };
    match radio.finish_transmit(frame.unwrap_or(&[])).await {
        Ok(()) => {
            master.on_sent();
            Ok(())
        }
        Err(e) => {
            master.on_skipped();
            Err(e)
        }
    }
}

/// Carries out one slot; on an error the master has been moved past it.
async fn run_slot<R: PacketRadio, C: LinkClock>(
    radio: &mut R,
    clock: &mut C,
    master: &mut Master,
    step: Step,
    buf: &mut [u8; FIFO_BYTES],
) -> Result<(), R::Error> {
    match step {
        Step::Transmit {
            channel,
            at_us,
            len,
        } => {
            // Too late for this slot once tuned (e.g. right after a radio recovery): an uplink
            // off the grid would drag the follower's grid with it, so the slot is skipped.
            let frame = buf.get(..len).unwrap_or(&[]);
            transmit_at(radio, clock, master, (channel, at_us, frame), true).await?;
        }
        Step::Listen {
            channel,
            from_us,
            until_us,
        } => {
            let heard = async {
                tune_until(radio, clock, channel, from_us).await?;
                // Listen on after a foreign or corrupted packet: ours may still come.
                while clock.now_us() < until_us {
                    let outcome = receive_until(radio, clock, buf, until_us).await?;
                    if master.on_received(outcome, buf, clock.now_us()) {
                        break;
                    }
                }
                Ok(())
            }
            .await;
            master.finish_listen();
            heard?;
        }
        Step::Idle => master.on_skipped(),
    }
    Ok(())
}
