//! `--plot DIR`: one figure per run, `DIR/<scenario>.png`, with four panels over time —
//! altitude and climb rate, attitude (true and estimated), the four motor commands, and the
//! link/arming state — with the fault, failsafe, disarm and touchdown marked.

use flight_app::outputs::Command;
use sim_plot::{Event, Figure, Panel, Series};

use super::Outcome;
use crate::world::Sample;

fn series(samples: &[Sample], name: &str, f: impl Fn(&Sample) -> f64) -> Series {
    let points: Vec<(f64, f64)> = samples.iter().map(|s| (s.t_s, f(s))).collect();
    Series::new(name, sim_plot::figure::decimate(&points))
}

fn level(on: bool, at: f64) -> f64 {
    if on { at + 0.8 } else { at }
}

/// The run's figure.
pub fn figure(o: &Outcome) -> Figure {
    let s = &o.sitl.samples;
    let r = &o.report;
    let mut events = Vec::new();
    if let Some(t) = r.fault_at_s {
        events.push(Event::new(t, "fault"));
    }
    if let Some(t) = r.fault_end_s {
        events.push(Event::new(t, "fault ends"));
    }
    if let Some(t) = r.failsafe_at_s {
        events.push(Event::new(t, "failsafe"));
    }
    if let Some(t) = r.disarmed_at_s {
        events.push(Event::new(t, "disarm"));
    }
    let with_events = |mut p: Panel| {
        for e in &events {
            p = p.event(e.clone());
        }
        p
    };
    let motor = |i: usize| {
        move |x: &Sample| match x.motors.get(i) {
            Some(Command::Throttle(v)) => f64::from(*v),
            _ => 0.0,
        }
    };
    Figure::new(format!(
        "flight-sitl {} at {}, seed {}",
        r.kind.name(),
        r.rate.name(),
        r.seed
    ))
    .x_label("time (s)")
    .panel(with_events(
        Panel::new("Altitude and climb rate", "m, m/s")
            .series(series(s, "altitude (m)", |x| x.altitude_m).width(2))
            .series(series(s, "climb (m/s)", |x| x.climb_mps).dashed()),
    ))
    .panel(with_events(
        Panel::new("Attitude", "deg")
            .series(series(s, "roll", |x| x.truth.euler_deg[0]))
            .series(series(s, "pitch", |x| x.truth.euler_deg[1]))
            .series(series(s, "roll est.", |x| f64::from(x.out.attitude.roll_deg)).dashed())
            .series(series(s, "pitch est.", |x| f64::from(x.out.attitude.pitch_deg)).dashed()),
    ))
    .panel(with_events(
        Panel::new("Motor commands (stopped = 0)", "throttle")
            .series(series(s, "m1", motor(0)))
            .series(series(s, "m2", motor(1)))
            .series(series(s, "m3", motor(2)))
            .series(series(s, "m4", motor(3))),
    ))
    .panel(with_events(
        Panel::new("Link and arming (high = on)", "state")
            .series(series(s, "powered", |x| level(x.flight_up, 0.0)))
            .series(series(s, "link up", |x| level(x.link_up, 1.0)))
            .series(series(s, "failsafe", |x| level(x.out.failsafe, 2.0)))
            .series(series(s, "armed", |x| level(x.out.armed, 3.0)))
            .y_range(-0.2, 4.0),
    ))
}
