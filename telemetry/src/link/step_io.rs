//! The radio side of a planned [`Step`](super::core::Step), alike at both ends: tune, wait
//! for the planned time, then send (and tell the state machine it was sent or skipped), or
//! receive with a timeout that ends at a planned time; and the power step written between
//! slots. The loops in `master` and `follower`
//! keep what differs — the master skipping a late uplink slot and listening on after a
//! foreign packet — and what they do with a received packet.

use super::core::{Follower, Master};
use super::radio::{LinkClock, LinkRx, PacketRadio};

/// What both state machines are told after a planned transmission.
pub(super) trait Sender {
    /// The planned frame went out.
    fn on_sent(&mut self);
    /// The planned step was not carried out.
    fn on_skipped(&mut self);
}

impl Sender for Master {
    fn on_sent(&mut self) {
        Master::on_sent(self);
    }
    fn on_skipped(&mut self) {
        Master::on_skipped(self);
    }
}

impl Sender for Follower {
    fn on_sent(&mut self) {
        Follower::on_sent(self);
    }
    fn on_skipped(&mut self) {
        Follower::on_skipped(self);
    }
}

/// Carries out a planned [`Step::Transmit`](super::core::Step::Transmit) of `frame`: tunes to `channel`, waits until
/// `at_us`, sends, and tells `end` it was sent. With `skip_late`, a transmission whose time
/// has already passed once tuned is not sent and `end` is told the step was skipped; so it
/// is on a radio error, which is then returned.
pub(super) async fn transmit_at<R: PacketRadio, C: LinkClock, S: Sender>(
    radio: &mut R,
    clock: &mut C,
    end: &mut S,
    (channel, at_us, frame): (u8, u64, &[u8]),
    skip_late: bool,
) -> Result<(), R::Error> {
    let sent = async {
        radio.set_channel(channel).await?;
        if skip_late && clock.now_us() > at_us {
            return Ok(false);
        }
        clock.sleep_until_us(at_us).await;
        radio.transmit(frame).await?;
        Ok(true)
    }
    .await;
    match sent {
        Ok(true) => end.on_sent(),
        Ok(false) => end.on_skipped(),
        Err(e) => {
            end.on_skipped();
            return Err(e);
        }
    }
    Ok(())
}

/// Writes the power step the state machine asks for (`wanted`) into the radio when it is not
/// the one written last (`applied`), between slots. A failed write counts as written: the
/// radio keeps the step for the recovery's re-configure.
pub(super) async fn apply_power<R: PacketRadio>(
    radio: &mut R,
    wanted: Option<u8>,
    applied: &mut Option<u8>,
) -> Result<(), R::Error> {
    let Some(step) = wanted.filter(|w| Some(*w) != *applied) else {
        return Ok(());
    };
    *applied = Some(step);
    radio.set_tx_power(step).await
}

/// Tunes to `channel` and waits until `from_us`, where a listen starts.
pub(super) async fn tune_until<R: PacketRadio, C: LinkClock>(
    radio: &mut R,
    clock: &mut C,
    channel: u8,
    from_us: u64,
) -> Result<(), R::Error> {
    radio.set_channel(channel).await?;
    clock.sleep_until_us(from_us).await;
    Ok(())
}

/// One receive into `buf` on the current channel, timing out at `until_us` (at once if that
/// has passed).
pub(super) async fn receive_until<R: PacketRadio, C: LinkClock>(
    radio: &mut R,
    clock: &mut C,
    buf: &mut [u8],
    until_us: u64,
) -> Result<LinkRx, R::Error> {
    let timeout = until_us.saturating_sub(clock.now_us());
    radio
        .receive(buf, u32::try_from(timeout).unwrap_or(u32::MAX))
        .await
}
