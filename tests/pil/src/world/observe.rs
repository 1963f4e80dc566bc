//! What the flight controller's state is, seen from outside as a pilot or a bench does:
//! the motor pins (armed: any motor turning — disarmed, every output is at its stopped
//! level), the buzzer (PC8, on while a tone sounds) played back against the alert patterns
//! of `flight_app::alerts` (the pilot hears "failsafe", "sensor fault", "control back",
//! "battery warning/critical"), and the telemetry the phone gets through the HM-10. The
//! image's RAM is never read: the PIL checks the image as hardware, so flight-sitl's record
//! (`LoopOutput`'s armed, failsafe and decision) is rebuilt from these observations after
//! the run, with hindsight (a pattern is recognised when its first tone ends; its event is
//! dated at the tone's start, within one 10 ms alert tick of the event itself).

use flight_app::alerts::Alert;
use flight_app::battery::BatteryLevel;
use flight_app::supervisor::Decision;

/// A flight MCU reset's motors-off may be seen this long before the record that saw the
/// reset (the handler stops them, then resets within microseconds), ns.
const RESET_SLACK_NS: u64 = 2_000_000;
/// A resumed flight runs its motors again within this long of the reset (the resume record
/// is fresh for 1 s; the resumed boot takes ≈ 80 ms), ns.
pub const RESUME_WINDOW_NS: u64 = 1_000_000_000;

/// How far an observed tone may be from a pattern's, ms (the firmware's alert task ticks
/// every 10 ms, so a tone lasts its length ± one tick).
const TOLERANCE_MS: f64 = 12.0;

/// What the buzzer's rhythm says (patterns that share a rhythm stay together).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Heard {
    /// Failsafe: three long low tones.
    Failsafe,
    /// The IMU failed, motors stopped; or an arm refused (same rhythm on a buzzer).
    SensorFaultOrArmRefused,
    /// Armed or disarmed (a rising or a falling pair: one rhythm on a buzzer).
    ArmedOrDisarmed,
    /// Control back after a failsafe.
    ControlRecovered,
    /// Battery warning.
    BatteryWarning,
    /// Battery critical.
    BatteryCritical,
    /// A mode change.
    Mode,
    /// The magnetometer calibration started, was stored or was refused.
    Magcal,
}

/// The first "on" interval and the gap after it, ms, of `alert`'s pattern as a buzzer
/// plays it (consecutive tones merge; a leading pause is silence).
fn rhythm(alert: Alert) -> (f64, Option<f64>) {
    let mut on = 0.0;
    let mut gap = None;
    let mut started = false;
    for t in alert.tones() {
        let ms = f64::from(t.duration_ms);
        match (t.frequency_hz != 0, started, gap) {
            (true, _, None) => {
                on += ms;
                started = true;
            }
            (false, true, None) => gap = Some(ms),
            // A leading pause is silence before the first tone.
            (false, false, None) => {}
            _ => break,
        }
    }
    (on, gap)
}

/// The pattern's length from its first tone, ms (a leading pause is not heard).
fn pattern_ms(alert: Alert) -> f64 {
    alert
        .tones()
        .iter()
        .skip_while(|t| t.frequency_hz == 0)
        .map(|t| f64::from(t.duration_ms))
        .sum()
}

fn heard_of(alert: Alert) -> Heard {
    match alert {
        Alert::Failsafe => Heard::Failsafe,
        Alert::SensorFault | Alert::ArmRefused => Heard::SensorFaultOrArmRefused,
        Alert::Armed | Alert::Disarmed => Heard::ArmedOrDisarmed,
        Alert::ControlRecovered => Heard::ControlRecovered,
        Alert::BatteryWarning => Heard::BatteryWarning,
        Alert::BatteryCritical => Heard::BatteryCritical,
        Alert::Mode(_) => Heard::Mode,
        Alert::MagcalStarted | Alert::MagcalStored | Alert::MagcalRefused => Heard::Magcal,
    }
}

const ALERTS: [Alert; 12] = [
    Alert::Failsafe,
    Alert::SensorFault,
    Alert::ArmRefused,
    Alert::Armed,
    Alert::Disarmed,
    Alert::ControlRecovered,
    Alert::BatteryWarning,
    Alert::BatteryCritical,
    Alert::Mode(telemetry::messages::FlightMode::Attitude),
    Alert::MagcalStarted,
    Alert::MagcalStored,
    Alert::MagcalRefused,
];

/// The alerts a buzzer trace played: (start ns, what), from its edges (ns, on) in order.
/// A pattern is told by its first tone's length and, where two share it, the gap after it.
pub fn alerts_heard(edges: &[(u64, bool)]) -> Vec<(u64, Heard)> {
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(&(start, on)) = edges.get(i) {
        if !on {
            i += 1;
            continue;
        }
        let Some(&(end, _)) = edges.get(i + 1) else {
            break;
        };
        let on_ms = (end - start) as f64 / 1e6;
        let gap_ms = edges.get(i + 2).map(|e| (e.0 - end) as f64 / 1e6);
        let distance = |a: &Alert| {
            let (on, gap) = rhythm(*a);
            let gap_off = match (gap, gap_ms) {
                (Some(g), Some(o)) => (g - o).abs(),
                (None, _) | (_, None) => 0.0,
            };
            ((on - on_ms).abs(), gap_off)
        };
        // The nearest first tone within the tolerance; of those, the nearest gap.
        let pick = ALERTS
            .into_iter()
            .filter(|a| distance(a).0 <= TOLERANCE_MS)
            .min_by(|a, b| {
                let (da, db) = (distance(a), distance(b));
                (da.1 + da.0).total_cmp(&(db.1 + db.0))
            });
        i += 2;
        if let Some(a) = pick {
            out.push((start, heard_of(a)));
            // The rest of its pattern is the same alert: skip its tones.
            let until = start + ((pattern_ms(a) - TOLERANCE_MS) * 1e6) as u64;
            while edges.get(i).is_some_and(|e| e.0 < until) {
                i += 1;
            }
        }
    }
    collapse_patterns(out)
}

/// One alert per pattern: repeats of the same rhythm within its own pattern's length (the
/// failsafe's three tones) are one.
fn collapse_patterns(heard: Vec<(u64, Heard)>) -> Vec<(u64, Heard)> {
    let mut out: Vec<(u64, Heard)> = Vec::new();
    for (t, h) in heard {
        let within = out
            .last()
            .is_some_and(|(t0, h0)| *h0 == h && t - t0 < 1_500_000_000);
        if !within {
            out.push((t, h));
        }
    }
    out
}

/// What the flight controller did at one instant, as observed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observed {
    /// Any motor turning.
    pub armed: bool,
    /// In link failsafe (heard, or told by telemetry).
    pub failsafe: bool,
    /// The supervisor's decision on this instant, as far as the outside can tell.
    pub decision: Decision,
    /// The battery level announced so far.
    pub battery: BatteryLevel,
}

/// Rebuilds the flight controller's state at each of `times` (ns, ascending) from the
/// motors (`armed`, per time), the buzzer's alerts, telemetry's failsafe flag where heard
/// (`telemetry_failsafe`: (ns, failsafe), ascending) and, for the disarm reason, whether the
/// pilot was making the disarm gesture then and whether the frame was airborne. Around a
/// reset of the flight MCU (`resets`, ns; not a power-on) the motors stopping is the reboot
/// (`Steady`, as flight-sitl records it), their coming back within [`RESUME_WINDOW_NS`] a
/// resumed flight (`Steady`: in failsafe until the link decides), and the "armed" tones
/// after it the link's word (`Resumed`).
pub fn rebuild(
    times: &[u64],
    armed: &[bool],
    heard: &[(u64, Heard)],
    telemetry_failsafe: &[(u64, bool)],
    gesture: &[bool],
    airborne: &[bool],
    resets: &[u64],
) -> Vec<Observed> {
    let mut out = Vec::with_capacity(times.len());
    let mut failsafe = false;
    let mut battery = BatteryLevel::Ok;
    let mut was_armed = false;
    let (mut hi, mut ti) = (0, 0);
    let mut awaiting_word = false;
    for (k, &t) in times.iter().enumerate() {
        let mut decision = Decision::Steady;
        let mut armed_tones = false;
        let since_reset = resets
            .iter()
            .rev()
            .find(|r| **r <= t + RESET_SLACK_NS)
            .map(|r| t.saturating_sub(*r));
        let near_reset = since_reset.is_some_and(|d| d <= RESUME_WINDOW_NS);
        while let Some(&(_, h)) = heard.get(hi).filter(|(th, _)| *th <= t) {
            hi += 1;
            match h {
                Heard::Failsafe => {
                    failsafe = true;
                    decision = Decision::FailsafeEntered;
                }
                Heard::ControlRecovered => {
                    failsafe = false;
                    decision = Decision::ControlRecovered;
                }
                Heard::BatteryWarning if battery == BatteryLevel::Ok => {
                    battery = BatteryLevel::Warning
                }
                Heard::BatteryCritical => battery = BatteryLevel::Critical,
                Heard::ArmedOrDisarmed => armed_tones = true,
                _ => {}
            }
        }
        while let Some(&(_, f)) = telemetry_failsafe.get(ti).filter(|(tt, _)| *tt <= t) {
            ti += 1;
            failsafe = f;
        }
        let now_armed = armed.get(k).copied().unwrap_or(false);
        if now_armed && !was_armed && near_reset {
            awaiting_word = true;
        } else if now_armed && !was_armed {
            decision = Decision::Armed;
        } else if was_armed && !now_armed && near_reset {
            // The fault handler stopped the motors and reset the MCU.
        } else if was_armed && !now_armed {
            // The alert that came with the disarm, within a tone's start.
            let near = |want: Heard| {
                heard
                    .iter()
                    .any(|(th, h)| *h == want && *th + 50_000_000 >= t && *th <= t + 100_000_000)
            };
            let up = airborne.get(k).copied().unwrap_or(false);
            decision = if near(Heard::SensorFaultOrArmRefused) {
                Decision::DisarmedSensorFault
            } else if failsafe {
                if up {
                    Decision::DisarmedLastResort
                } else {
                    Decision::DisarmedFailsafe
                }
            } else if gesture.get(k).copied().unwrap_or(false) {
                Decision::DisarmedByPilot
            } else {
                Decision::DisarmedIdle
            };
        }
        if awaiting_word && now_armed && armed_tones {
            awaiting_word = false;
            decision = Decision::Resumed;
        }
        awaiting_word &= now_armed;
        was_armed = now_armed;
        out.push(Observed {
            armed: now_armed,
            failsafe,
            decision,
            battery,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The buzzer edges `alert` makes from `t0` ns.
    fn play(alert: Alert, t0: u64) -> Vec<(u64, bool)> {
        let mut t = t0;
        let mut out: Vec<(u64, bool)> = Vec::new();
        for tone in alert.tones() {
            let on = tone.frequency_hz != 0;
            if (on || !out.is_empty()) && out.last().map(|e| e.1) != Some(on) {
                out.push((t, on));
            }
            t += u64::from(tone.duration_ms) * 1_000_000;
        }
        if out.last().map(|e| e.1) == Some(true) {
            out.push((t, false));
        }
        out
    }

    #[test]
    fn each_pattern_is_told_by_its_rhythm() {
        for (alert, heard) in [
            (Alert::Failsafe, Heard::Failsafe),
            (Alert::SensorFault, Heard::SensorFaultOrArmRefused),
            (Alert::ArmRefused, Heard::SensorFaultOrArmRefused),
            (Alert::Armed, Heard::ArmedOrDisarmed),
            (Alert::Disarmed, Heard::ArmedOrDisarmed),
            (Alert::ControlRecovered, Heard::ControlRecovered),
            (Alert::BatteryWarning, Heard::BatteryWarning),
            (Alert::BatteryCritical, Heard::BatteryCritical),
        ] {
            let edges = play(alert, 1_000_000_000);
            let got = alerts_heard(&edges);
            assert_eq!(got.len(), 1, "{alert:?}: {got:?}");
            assert_eq!(got[0].1, heard, "{alert:?}");
        }
        // Failsafe is dated at its first tone.
        assert_eq!(alerts_heard(&play(Alert::Failsafe, 7))[0].0, 7);
    }

    #[test]
    fn a_sequence_of_alerts_and_the_rebuilt_state() {
        // Armed at 1 s, failsafe heard at 5 s, disarmed on the ground at 20 s.
        let mut edges = play(Alert::Armed, 1_000_000_000);
        edges.extend(play(Alert::Failsafe, 5_000_000_000));
        edges.extend(play(Alert::Disarmed, 20_000_000_000));
        let heard = alerts_heard(&edges);
        assert_eq!(
            heard.iter().map(|h| h.1).collect::<Vec<_>>(),
            vec![
                Heard::ArmedOrDisarmed,
                Heard::Failsafe,
                Heard::ArmedOrDisarmed
            ]
        );
        let times: Vec<u64> = (0..30).map(|s| s * 1_000_000_000).collect();
        let armed: Vec<bool> = times
            .iter()
            .map(|t| (1_000_000_000..20_000_000_000).contains(t))
            .collect();
        let airborne = vec![false; times.len()];
        let got = rebuild(
            &times,
            &armed,
            &heard,
            &[],
            &vec![false; times.len()],
            &airborne,
            &[],
        );
        assert_eq!(got[1].decision, Decision::Armed);
        assert!(!got[4].failsafe && got[5].failsafe);
        assert_eq!(got[5].decision, Decision::FailsafeEntered);
        assert_eq!(got[20].decision, Decision::DisarmedFailsafe);
        assert!(!got[21].armed);
        // A sensor-fault siren at the disarm names it.
        let mut edges = play(Alert::Armed, 1_000_000_000);
        edges.extend(play(Alert::SensorFault, 10_000_000_000));
        let heard = alerts_heard(&edges);
        let armed: Vec<bool> = times
            .iter()
            .map(|t| (1_000_000_000..10_000_000_000).contains(t))
            .collect();
        let got = rebuild(
            &times,
            &armed,
            &heard,
            &[],
            &vec![false; times.len()],
            &airborne,
            &[],
        );
        assert_eq!(got[10].decision, Decision::DisarmedSensorFault);
        // Telemetry's flag counts too.
        let got = rebuild(
            &times,
            &armed,
            &[],
            &[(3_000_000_000, true)],
            &vec![false; times.len()],
            &airborne,
            &[],
        );
        assert!(got[3].failsafe && !got[2].failsafe);
    }

    #[test]
    fn a_reset_in_the_air_is_a_reboot_and_the_armed_tones_after_it_the_links_word() {
        // 1 ms records; armed at 10 ms; the handler stops the motors at 100 ms and the reset
        // is seen at 101 ms; the resumed boot runs them from 180 ms, the link's word (the
        // armed tones) at 210 ms.
        let ms = 1_000_000;
        let times: Vec<u64> = (0..400).map(|k| k * ms).collect();
        let armed: Vec<bool> = times
            .iter()
            .map(|t| (10 * ms..100 * ms).contains(t) || *t >= 180 * ms)
            .collect();
        let heard = alerts_heard(&play(Alert::Armed, 210 * ms));
        let n = times.len();
        let got = rebuild(
            &times,
            &armed,
            &heard,
            &[],
            &vec![false; n],
            &vec![true; n],
            &[101 * ms],
        );
        assert_eq!(got[10].decision, Decision::Armed);
        assert_eq!(
            got[100].decision,
            Decision::Steady,
            "the reboot, not a disarm"
        );
        assert!(!got[100].armed && got[180].armed);
        assert_eq!(
            got[180].decision,
            Decision::Steady,
            "resumed, not armed anew"
        );
        let word: Vec<usize> = (0..n)
            .filter(|k| got[*k].decision == Decision::Resumed)
            .collect();
        assert_eq!(word, vec![210]);
        // Without the reset the same motors are a disarm and a new arming.
        let got = rebuild(
            &times,
            &armed,
            &heard,
            &[],
            &vec![false; n],
            &vec![true; n],
            &[],
        );
        assert_eq!(got[100].decision, Decision::DisarmedIdle);
        assert_eq!(got[180].decision, Decision::Armed);
    }
}
