//! The replaying attackers: frames the link sent once, sent again in a later slot with the
//! same on-air number — the same channel, the right time, a tag that was valid 256·k slots
//! earlier.

use telemetry::link::{PacketRadio, SlotKind};

use super::Victim;
use super::grid::{Action, SlotAttacker, follow_grid, is_nonce};
use crate::driver::SimClock;
use crate::probe::Shared;

/// `--attack replay`: alternates by wrap of the 8-bit slot counter: in even wraps it
/// listens and records every frame; in odd wraps it sends recordings again (older ones in
/// turn, so frames from before a flight restart too) in one slot in five, and in every slot
/// whose recordings include an epoch-nonce frame.
struct Replayer {
    recordings: Vec<Vec<Vec<u8>>>,
}

impl SlotAttacker for Replayer {
    fn plan(&mut self, k: u64, _kind: SlotKind) -> Action {
        if (k / 256).is_multiple_of(2) {
            return Action::Listen;
        }
        let Some(old) = self.recordings.get((k % 256) as usize) else {
            return Action::Idle;
        };
        let nonce = old.iter().rposition(|f| is_nonce(f));
        let pick = match nonce {
            Some(i) => Some(i),
            None if k.is_multiple_of(5) && !old.is_empty() => Some((k / 512) as usize % old.len()),
            None => None,
        };
        pick.and_then(|i| old.get(i))
            .map_or(Action::Idle, |f| Action::Send(f.clone()))
    }

    fn heard(&mut self, k: u64, _kind: SlotKind, frame: &[u8]) {
        if let Some(r) = self.recordings.get_mut((k % 256) as usize) {
            r.push(frame.to_vec());
        }
    }
}

pub(super) async fn replay<R: PacketRadio>(
    mut radio: R,
    mut clock: SimClock,
    victim: &Victim,
    record: &Shared,
) -> Result<(), R::Error> {
    radio.configure(&victim.config).await?;
    let mut replayer = Replayer {
        recordings: vec![Vec::new(); 256],
    };
    follow_grid(&mut radio, &mut clock, victim, &mut replayer, record).await
}

/// `--attack nonce-replay` (issue 30, finding 3): listens in every slot and records the
/// flight side's epoch-nonce frames with their on-air slot number. Once it holds nonce
/// frames of two of the flight side's sessions (it was power-cycled between), it attacks
/// every downlink slot whose on-air number one of them names: it jams the downlink slot
/// before it at the module (the module misses that downlink, so the epoch looks quiet) and
/// replays the recorded frame in the slot itself — again in every wrap.
struct NonceReplayer {
    ratio: u64,
    /// Nonce frames heard, by on-air slot number, with their nonce.
    nonce_frames: Vec<Option<Vec<u8>>>,
    /// Distinct follower nonces heard (a new one: a new session or a resync).
    nonces: Vec<u64>,
}

impl NonceReplayer {
    fn attacking(&self) -> bool {
        self.nonces.len() >= 2
    }

    fn recorded(&self, on_air: u64) -> Option<&Vec<u8>> {
        self.nonce_frames
            .get((on_air % 256) as usize)
            .and_then(Option::as_ref)
    }
}

impl SlotAttacker for NonceReplayer {
    fn plan(&mut self, k: u64, kind: SlotKind) -> Action {
        if !self.attacking() || kind != SlotKind::Downlink {
            return Action::Listen;
        }
        if let Some(frame) = self.recorded(k) {
            return Action::Send(frame.clone());
        }
        // The downlink slot before a replay: jammed (with the same frame: any frame that
        // starts first captures the module's receiver).
        match self.recorded(k + self.ratio) {
            Some(frame) => Action::Send(frame.clone()),
            None => Action::Listen,
        }
    }

    fn heard(&mut self, k: u64, kind: SlotKind, frame: &[u8]) {
        if kind != SlotKind::Downlink || !is_nonce(frame) {
            return;
        }
        // Version, kind, slot, then the 64-bit nonce in clear.
        let Some(nonce) = frame
            .get(3..11)
            .and_then(|b| <[u8; 8]>::try_from(b).ok())
            .map(u64::from_le_bytes)
        else {
            return;
        };
        if !self.nonces.contains(&nonce) {
            self.nonces.push(nonce);
        }
        if let Some(slot) = self.nonce_frames.get_mut((k % 256) as usize) {
            *slot = Some(frame.to_vec());
        }
    }
}

pub(super) async fn nonce_replay<R: PacketRadio>(
    mut radio: R,
    mut clock: SimClock,
    victim: &Victim,
    record: &Shared,
) -> Result<(), R::Error> {
    radio.configure(&victim.config).await?;
    let mut replayer = NonceReplayer {
        ratio: u64::from(victim.schedule.telemetry_ratio.max(1)),
        nonce_frames: vec![None; 256],
        nonces: Vec::new(),
    };
    follow_grid(&mut radio, &mut clock, victim, &mut replayer, record).await
}
