//! Following the victim link's slot grid from a third radio: slot number and timing come
//! from the uplinks, which carry the slot in clear; every slot the attacker then listens
//! in, sends a frame in, or lets pass, as its [`SlotAttacker`] says.

use telemetry::link::{HOP_CHANNELS, LinkRx, PacketRadio, SlotKind};

use super::Victim;
use crate::driver::SimClock;

/// Slots without an uplink heard after which the grid counts as lost (clock drift between
/// the attacker and the module is a few µs per wrap; the link may have gone quiet).
const LOST_AFTER_SLOTS: u64 = 640;
/// How much earlier than the slot start the receiver is opened.
const LISTEN_LEAD_US: u64 = 100;

/// What the attacker does in one slot.
pub(crate) enum Action {
    /// Receive on the slot's channel for its listening window.
    Listen,
    /// Send this frame at the slot start (a lead shorter than the link's own: the frame's
    /// sync word arrives first and, about as loud or louder, captures the receiver).
    Send(Vec<u8>),
    /// Nothing (the slot passes).
    Idle,
}

/// An attacker that follows the grid.
pub(crate) trait SlotAttacker {
    /// What to do in slot `k` (the attacker's count; its on-air number is `k % 256`), a
    /// slot of `kind`.
    fn plan(&mut self, k: u64, kind: SlotKind) -> Action;
    /// A frame heard in slot `k` that names it.
    fn heard(&mut self, k: u64, kind: SlotKind, frame: &[u8]);
    /// Whether the attacker is done (the grid is left).
    fn done(&self) -> bool {
        false
    }
}

/// Whether a link frame is an uplink (the master's: channels or its epoch nonce).
pub(crate) fn is_uplink(frame: &[u8]) -> bool {
    frame
        .get(1)
        .is_some_and(|k| matches!(k & 0x07, 2 | 3 | 5 | 6))
}

/// Whether a sealed link frame carries an epoch nonce (kind bit 6).
pub(crate) fn is_nonce(frame: &[u8]) -> bool {
    frame.get(1).is_some_and(|k| k & 0x40 != 0)
}

/// The slot grid as heard: slot `k` of the attacker's count started at `start_us`.
#[derive(Clone, Copy)]
struct Anchor {
    k: u64,
    start_us: u64,
}

/// Follows `victim`'s grid with `attacker` until it is done: acquires (dwells on one hop
/// channel until an uplink names its slot), then walks the slots; acquires again when no
/// uplink was heard for a while.
pub(crate) async fn follow_grid<R: PacketRadio>(
    radio: &mut R,
    clock: &mut SimClock,
    victim: &Victim,
    attacker: &mut impl SlotAttacker,
    record: &crate::probe::Shared,
) -> Result<(), R::Error> {
    let schedule = victim.schedule;
    let slot_us = u64::from(schedule.slot_us());
    let mut buf = [0u8; 64];
    // The attacker's count goes on across acquisitions (each slot named once).
    let mut base = 0u64;
    while !attacker.done() {
        radio.set_channel(victim.hops.channel(0)).await?;
        let timeout = u32::try_from(2 * (HOP_CHANNELS as u64 + 1) * slot_us).unwrap_or(u32::MAX);
        let LinkRx::Packet { len, .. } = radio.receive(&mut buf, timeout).await? else {
            continue;
        };
        let frame = buf.get(..len).unwrap_or(&[]);
        let (true, Some(&slot)) = (is_uplink(frame), frame.get(2)) else {
            continue;
        };
        // Continue the count on the heard on-air number.
        let k0 = (base & !0xFF) + 256 + u64::from(slot);
        let mut anchor = Anchor {
            k: k0,
            start_us: clock
                .now_us()
                .saturating_sub(u64::from(schedule.packet_end_offset_us(len))),
        };
        let mut k = k0 + 1;
        while !attacker.done() && k - anchor.k < LOST_AFTER_SLOTS {
            let start = anchor.start_us + (k - anchor.k) * slot_us;
            if clock.now_us() + 50 > start {
                k += 1;
                continue;
            }
            let on_air = (k % 256) as u8;
            let kind = schedule.kind(k as u32);
            let action = attacker.plan(k, kind);
            if !matches!(action, Action::Idle) {
                radio
                    .set_channel(victim.hops.channel_for_slot(k as u32))
                    .await?;
            }
            match action {
                Action::Idle => {}
                Action::Send(frame) => {
                    clock.sleep_until_us(start).await;
                    radio.transmit(&frame).await?;
                    record.borrow_mut().attacker_sent += 1;
                }
                Action::Listen => {
                    clock
                        .sleep_until_us(start.saturating_sub(LISTEN_LEAD_US))
                        .await;
                    let until = start + u64::from(schedule.listen_end_offset_us());
                    let timeout = u32::try_from(until.saturating_sub(clock.now_us())).unwrap_or(0);
                    if let LinkRx::Packet { len, .. } = radio.receive(&mut buf, timeout).await?
                        && buf.get(2) == Some(&on_air)
                    {
                        let frame = buf.get(..len).unwrap_or(&[]);
                        attacker.heard(k, kind, frame);
                        if is_uplink(frame) {
                            anchor = Anchor {
                                k,
                                start_us: clock
                                    .now_us()
                                    .saturating_sub(u64::from(schedule.packet_end_offset_us(len))),
                            };
                        }
                    }
                }
            }
            k += 1;
        }
        base = k;
    }
    Ok(())
}
