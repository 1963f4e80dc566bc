//! Plays alerts one after another, most important first. Sans-IO: `tick` says which
//! frequency should sound now; the firmware retunes the DAC timer (or the buzzer PWM) when
//! it changes.

use heapless::Vec;

use super::patterns::Alert;

/// Queue depth: more than this many distinct alerts at once means the least important wait
/// their turn is lost, which is fine — the state they announce is reported in telemetry.
const QUEUE: usize = 8;

/// Removes and returns the `i`-th queued alert, keeping the others' order (ties go to the
/// earliest queued). `retain` has no panic path, unlike `Vec::remove`'s bounds assert.
fn take(queue: &mut Vec<Alert, QUEUE>, i: usize) -> Option<Alert> {
    let mut index = 0;
    let mut taken = None;
    queue.retain(|a| {
        let keep = index != i;
        if !keep {
            taken = Some(*a);
        }
        index += 1;
        keep
    });
    taken
}

/// The sequencer.
#[derive(Debug, Clone)]
pub struct TonePlayer {
    queue: Vec<Alert, QUEUE>,
    playing: Option<Playing>,
    repeat: Option<Repeat>,
}

#[derive(Debug, Clone, Copy)]
struct Playing {
    alert: Alert,
    tone: usize,
    tone_started_ms: u32,
}

#[derive(Debug, Clone, Copy)]
struct Repeat {
    alert: Alert,
    period_ms: u32,
    last_ms: Option<u32>,
}

impl Default for TonePlayer {
    fn default() -> Self {
        Self::new()
    }
}

impl TonePlayer {
    /// Silent player.
    pub const fn new() -> Self {
        Self {
            queue: Vec::new(),
            playing: None,
            repeat: None,
        }
    }

    /// Queues an alert. A duplicate of one already waiting is ignored; a more important one
    /// interrupts a less important one playing; with a full queue the least important goes.
    pub fn push(&mut self, alert: Alert) {
        if self.queue.contains(&alert) {
            return;
        }
        if let Some(p) = self.playing
            && alert.priority() > p.alert.priority()
        {
            self.playing = None;
        }
        if self.queue.is_full() {
            let weakest = self
                .queue
                .iter()
                .enumerate()
                .min_by_key(|(_, a)| a.priority())
                .map(|(i, a)| (i, a.priority()));
            match weakest {
                Some((i, p)) if p < alert.priority() => {
                    take(&mut self.queue, i);
                }
                _ => return,
            }
        }
        // Cannot fail: there is room now.
        let _ = self.queue.push(alert);
    }

    /// Repeats `alert` every `period_ms` (battery alarms) until replaced or cleared.
    pub fn set_repeating(&mut self, alert: Option<Alert>, period_ms: u32) {
        match (alert, self.repeat) {
            (Some(a), Some(r)) if r.alert == a && r.period_ms == period_ms => {}
            (Some(alert), _) => {
                self.repeat = Some(Repeat {
                    alert,
                    period_ms,
                    last_ms: None,
                })
            }
            (None, _) => self.repeat = None,
        }
    }

    /// The frequency to sound at `now_ms` (0 = silence).
    pub fn tick(&mut self, now_ms: u32) -> u16 {
        if let Some(r) = &mut self.repeat
            && r.last_ms
                .is_none_or(|last| now_ms.wrapping_sub(last) >= r.period_ms)
        {
            r.last_ms = Some(now_ms);
            let alert = r.alert;
            self.push(alert);
        }
        loop {
            let Some(mut p) = self.playing.take().or_else(|| self.next(now_ms)) else {
                return 0;
            };
            let tones = p.alert.tones();
            let Some(tone) = tones.get(p.tone) else {
                continue; // finished: take the next alert
            };
            if now_ms.wrapping_sub(p.tone_started_ms) < u32::from(tone.duration_ms) {
                self.playing = Some(p);
                return tone.frequency_hz;
            }
            p.tone_started_ms = p.tone_started_ms.wrapping_add(u32::from(tone.duration_ms));
            p.tone += 1;
            self.playing = Some(p);
        }
    }

    fn next(&mut self, now_ms: u32) -> Option<Playing> {
        let (i, _) = self
            .queue
            .iter()
            .enumerate()
            .max_by_key(|(i, a)| (a.priority(), core::cmp::Reverse(*i)))?;
        let alert = take(&mut self.queue, i)?;
        Some(Playing {
            alert,
            tone: 0,
            tone_started_ms: now_ms,
        })
    }

    /// Nothing playing or waiting.
    pub fn is_idle(&self) -> bool {
        self.playing.is_none() && self.queue.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::supervisor::FlightMode;

    /// Frequencies sounded every 10 ms from `from` to `to`.
    fn record(p: &mut TonePlayer, from: u32, to: u32) -> std::vec::Vec<u16> {
        (from..to).step_by(10).map(|t| p.tick(t)).collect()
    }

    #[test]
    fn plays_the_armed_pattern_then_falls_silent() {
        let mut p = TonePlayer::new();
        p.push(Alert::Armed);
        let f = record(&mut p, 0, 600);
        assert!(f[..15].iter().all(|&x| x == 1000));
        assert!(f[15..45].iter().all(|&x| x == 2000));
        assert!(f[45..].iter().all(|&x| x == 0));
        assert!(p.is_idle());
    }

    #[test]
    fn higher_priority_interrupts_and_order_follows_priority() {
        let mut p = TonePlayer::new();
        p.push(Alert::Mode(FlightMode::Attitude));
        assert_eq!(p.tick(0), 3000);
        p.push(Alert::Disarmed);
        p.push(Alert::Failsafe);
        // The failsafe tone cuts in at once, then the disarm, then nothing (mode was cut).
        assert_eq!(p.tick(10), 600);
        let f = record(&mut p, 20, 4000);
        let first_disarm = f.iter().position(|&x| x == 2000).unwrap();
        assert!(f[..first_disarm].iter().all(|&x| x == 600 || x == 0));
        assert!(
            !f.contains(&3000),
            "the interrupted mode beep is dropped, not replayed"
        );
    }

    #[test]
    fn repeating_alarm_comes_back_every_period() {
        let mut p = TonePlayer::new();
        p.set_repeating(Some(Alert::BatteryCritical), 2_000);
        let f = record(&mut p, 0, 6_000);
        let starts = (1..f.len())
            .filter(|&i| f[i] == 4000 && f[i - 1] != 4000)
            .count()
            + usize::from(f[0] == 4000);
        assert_eq!(starts, 9, "three beeps per pattern, three patterns in 6 s");
        p.set_repeating(None, 0);
        let quiet = record(&mut p, 6_000, 9_000);
        assert!(quiet.iter().skip(100).all(|&x| x == 0));
    }

    #[test]
    fn full_queue_drops_the_least_important() {
        let mut p = TonePlayer::new();
        let modes = [
            FlightMode::RatePid,
            FlightMode::RateLqg,
            FlightMode::Attitude,
            FlightMode::Horizon,
            FlightMode::SystemId,
        ];
        for m in modes {
            p.push(Alert::Mode(m));
        }
        for a in [Alert::Armed, Alert::ControlRecovered, Alert::ArmRefused] {
            p.push(a);
        }
        assert_eq!(p.queue.len(), 8);
        p.push(Alert::BatteryCritical);
        assert!(p.queue.contains(&Alert::BatteryCritical));
        assert_eq!(p.queue.len(), 8);
        assert_eq!(p.tick(0), 4000, "most important first");
    }
}
