//! The hold scenarios' timeline (when the pilot engages the hold, when it pushes the pitch
//! stick in loiter, when the measuring starts) and their figures, measured on the truth:
//! how far the altitude and the horizontal position stray from what was held, and for the
//! link cut with a GPS fix how far the failsafe's position hold drifts.

use flight_app::supervisor::FlightMode;

use super::Kind;
use super::pilot::Push;
use crate::metrics::{window, worst};
use crate::world::{Sample, Sitl};

/// From the start of the pilot's altitude-keeping (glances) to the switch flick, s: the
/// climb spent and the frame settled.
pub const ENGAGE_AFTER_S: f64 = 5.0;
/// Altitude hold: settling from the engagement to the measured minute, s.
pub const ALTITUDE_SETTLE_S: f64 = 4.0;
/// Position hold and loiter: settling from the engagement (the wind's drag learnt by the
/// velocity integral) to the measuring, s.
pub const POSITION_SETTLE_S: f64 = 10.0;
/// Altitude and position hold: the measured time, s.
pub const MEASURE_S: f64 = 60.0;
/// Loiter: the pitch stick pushed forward this far …
pub const LOITER_PITCH: f32 = -0.5;
/// … for this long, s.
pub const LOITER_PUSH_S: f64 = 3.0;
/// Loiter: from the release to the measuring of the new position (the frame brakes onto
/// the held position), s.
pub const LOITER_SETTLE_S: f64 = 8.0;
/// Loiter: the new position watched this long, s.
pub const LOITER_MEASURE_S: f64 = 30.0;
/// Link cut with a fix: the failsafe's hold is measured from this long after its start
/// (the climb the frame had at the cut arrested) …
pub const FAILSAFE_SETTLE_S: f64 = 2.5;
/// … until this long before the hold ends and the descent starts, s.
pub const FAILSAFE_HOLD_MARGIN_S: f64 = 0.5;

/// When things happen in a hold scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timeline {
    /// The mode switch goes high, s.
    pub engage_s: f64,
    /// Loiter's push of the pitch stick.
    pub push: Option<Push>,
    /// The measuring starts, s.
    pub measure_from_s: f64,
    /// The scenario ends, s.
    pub end_s: f64,
}

impl Timeline {
    /// The timeline of hold scenario `kind` whose pilot starts keeping the altitude at
    /// `hold_from_s`.
    pub fn of(kind: Kind, hold_from_s: f64) -> Self {
        let engage_s = hold_from_s + ENGAGE_AFTER_S;
        match kind {
            Kind::Loiter => {
                let from_s = engage_s + POSITION_SETTLE_S;
                let to_s = from_s + LOITER_PUSH_S;
                let measure_from_s = to_s + LOITER_SETTLE_S;
                Self {
                    engage_s,
                    push: Some(Push {
                        from_s,
                        to_s,
                        pitch: LOITER_PITCH,
                    }),
                    measure_from_s,
                    end_s: measure_from_s + LOITER_MEASURE_S,
                }
            }
            Kind::PositionHold => Self {
                engage_s,
                push: None,
                measure_from_s: engage_s + POSITION_SETTLE_S,
                end_s: engage_s + POSITION_SETTLE_S + MEASURE_S,
            },
            _ => Self {
                engage_s,
                push: None,
                measure_from_s: engage_s + ALTITUDE_SETTLE_S,
                end_s: engage_s + ALTITUDE_SETTLE_S + MEASURE_S,
            },
        }
    }
}

/// What a hold did (every figure None where the scenario has none).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Figures {
    /// The flight controller entered the held mode (the first loop in it), s.
    pub engaged_at_s: Option<f64>,
    /// Worst |altitude − altitude held| over the measured time, m.
    pub altitude_error_max_m: Option<f64>,
    /// Twice the RMS horizontal distance from the held position over the measured time, m.
    pub position_error_2sigma_m: Option<f64>,
    /// Worst horizontal distance from the held position over the measured time, m.
    pub position_error_max_m: Option<f64>,
    /// Loiter: how far the push moved the frame (its position at the push to its position
    /// settled after the release), m.
    pub loiter_moved_m: Option<f64>,
    /// Worst horizontal distance from the new position (loiter, after the push) or from
    /// the position at the failsafe (link cut with a fix, over the failsafe's hold), m.
    pub held_position_drift_m: Option<f64>,
}

fn horizontal(a: &Sample, b: &Sample) -> f64 {
    let (p, q) = (a.truth.state.position_m, b.truth.state.position_m);
    (p[0] - q[0]).hypot(p[1] - q[1])
}

fn at(s: &[Sample], t: f64) -> Option<&Sample> {
    s.iter().find(|x| x.t_s >= t)
}

/// The position figures of `w` around `origin`: (2σ, worst).
fn spread(w: &[&Sample], origin: &Sample) -> (Option<f64>, Option<f64>) {
    if w.is_empty() {
        return (None, None);
    }
    #[allow(clippy::cast_precision_loss)]
    let n = w.len() as f64;
    let rms = (w.iter().map(|x| horizontal(x, origin).powi(2)).sum::<f64>() / n).sqrt();
    (Some(2.0 * rms), Some(worst(w, |x| horizontal(x, origin))))
}

/// The figures of a hold scenario `kind` flown as `timeline`, until `end_s`.
pub fn measure(sitl: &Sitl, kind: Kind, timeline: &Timeline, end_s: f64) -> Figures {
    let s = &sitl.samples;
    let mode = match kind {
        Kind::AltitudeHold => FlightMode::AltitudeHold,
        Kind::PositionHold => FlightMode::PositionHold,
        Kind::Loiter => FlightMode::Loiter,
        _ => return Figures::default(),
    };
    let Some(engaged) = s
        .iter()
        .find(|x| x.t_s >= timeline.engage_s && x.out.mode == mode)
    else {
        return Figures::default();
    };
    let w = window(s, timeline.measure_from_s, end_s);
    let altitude_error_max_m =
        (!w.is_empty()).then(|| worst(&w, |x| x.altitude_m - engaged.altitude_m));
    let mut f = Figures {
        engaged_at_s: Some(engaged.t_s),
        altitude_error_max_m,
        ..Figures::default()
    };
    match kind {
        Kind::PositionHold => {
            (f.position_error_2sigma_m, f.position_error_max_m) = spread(&w, engaged);
        }
        Kind::Loiter => {
            let start = timeline.push.and_then(|p| at(s, p.from_s));
            if let (Some(start), Some(new)) = (start, at(s, timeline.measure_from_s)) {
                f.loiter_moved_m = Some(horizontal(new, start));
                let (two_sigma, max) = spread(&w, new);
                f.position_error_2sigma_m = two_sigma;
                f.held_position_drift_m = max;
            }
        }
        _ => {}
    }
    f
}

/// Link cut with a fix: (worst horizontal drift, worst altitude change) from the failsafe's
/// start over its position hold (`hold_s` long).
pub fn failsafe_hold(sitl: &Sitl, failsafe_at_s: f64, hold_s: f64) -> Option<(f64, f64)> {
    let s = &sitl.samples;
    let origin = at(s, failsafe_at_s)?;
    let w = window(
        s,
        failsafe_at_s + FAILSAFE_SETTLE_S,
        failsafe_at_s + hold_s - FAILSAFE_HOLD_MARGIN_S,
    );
    if w.is_empty() {
        return None;
    }
    Some((
        worst(&w, |x| horizontal(x, origin)),
        worst(&w, |x| x.altitude_m - origin.altitude_m),
    ))
}
