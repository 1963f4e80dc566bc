//! The master's async loop: a thin shell that runs [`Master`]'s steps on a radio and a clock,
//! one slot after another on its own time base, and lets the application exchange channels
//! and telemetry with the state machine at every slot boundary.

use super::bind::{BIND_KEY, LinkParams, OFFER_PERIOD_US, bind_radio_config, is_accept_of};
use super::core::{Master, Step};
use super::radio::{LinkClock, PacketRadio, LinkRx};
use super::rate::FIFO_BYTES;
use super::recovery::Recovery;
use super::schedule::SlotKind;
use super::step_io::{receive_until, transmit_at, tune_until};
use crate::frame::{Frame, encode};

/// Bind mode on the master (started by the bind button/command): offers `params` on the
/// band's bind channel every [`OFFER_PERIOD_US`] and listens in between, until a follower
/// accepts (true) or `timeout_us` passes (false).
pub async fn bind_master<R: PacketRadio, C: LinkClock>(
    radio: &mut R,
    clock: &mut C,
    params: &LinkParams,
    timeout_us: u64,
) -> Result<bool, R::Error> {
    radio.configure(&bind_radio_config(params.band)).await?;
    radio.set_channel(0).await?;
    let give_up = clock.now_us() + timeout_us;
    let mut offer = [0u8; FIFO_BYTES];
    let Ok(offer_len) = encode(&Frame::BindOffer(params.offer()), BIND_KEY, &mut offer) else {
        return Ok(false);
    };
    // An offer that cannot be built is no bind (never an empty frame on the air).
    let Some(offer) = offer.get(..offer_len) else {
        return Ok(false);
    };
    let mut buf = [0u8; FIFO_BYTES];
    while clock.now_us() < give_up {
        let period_end = clock.now_us() + u64::from(OFFER_PERIOD_US);
        radio.transmit(offer).await?;
        while clock.now_us() < period_end {
            if let LinkRx::Packet { len, .. } =
                receive_until(radio, clock, &mut buf, period_end).await?
                && buf
                    .get(..len)
                    .is_some_and(|packet| is_accept_of(packet, params))
            {
                return Ok(true);
            }
        }
    }
    Ok(false)
}

/// How long before an uplink's transmission the application is asked for its channels and
/// the frame is built: room for building it (pack, CRC: tens of µs on the nRF52840) and the
/// hop-register write before the transmission starts.
pub const LATCH_BEFORE_TX_US: u32 = 30;

/// The application side of a master: called once per slot — at the start of a downlink slot,
/// and [`LATCH_BEFORE_TX_US`] before the transmission of an uplink, so the channels it sets
/// are as fresh as the slot allows.
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
    loop {
        // Fell behind by a whole slot (a debugger, a radio reset): skip, keep the grid.
        while clock.now_us() > slot_start_us + slot_us / 2 {
            master.on_skipped();
            slot_start_us += slot_us;
        }
        // Channels are latched right before the uplink is built and sent, not at the slot
        // start: every uplink then carries the freshest handset input the slot allows.
        if master.schedule().kind(master.slot()) == SlotKind::Uplink {
            let tx_lead = master.schedule().rate.tx_lead_us();
            let latch = slot_start_us + u64::from(tx_lead.saturating_sub(LATCH_BEFORE_TX_US));
            clock.sleep_until_us(latch).await;
        }
        hooks.on_slot(slot_start_us, master);
        let step = master.plan(slot_start_us, &mut buf);
        let result = run_slot(radio, clock, master, step, &mut buf).await;
        recovery
            .after_step(radio, clock, &config, result, || master.on_radio_error())
            .await?;
        slot_start_us += slot_us;
        clock.sleep_until_us(slot_start_us).await;
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
