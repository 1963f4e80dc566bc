//! The link figure of `taulink-sim --plot DIR`: link quality both ways, RSSI at both ends,
//! channel updates per second and latency over virtual time, one status sample per virtual
//! second, with the path cut and the failsafe entry/exit marked. Drawn by `sim-plot`.

use sim_plot::{Event, Figure, Panel, Series};

use crate::{Report, Scenario, Status};

/// The status samples of one run (collect them in `run`'s status callback).
#[derive(Clone, Debug, Default)]
pub struct Trace {
    samples: Vec<Status>,
}

impl Trace {
    /// Keeps one status sample.
    pub fn push(&mut self, s: &Status) {
        self.samples.push(*s);
    }

    fn series(&self, f: impl Fn(&Status) -> Option<f64>) -> Vec<(f64, f64)> {
        self.samples
            .iter()
            .filter_map(|s| f(s).map(|v| (s.time_s, v)))
            .collect()
    }

    /// The figure of this run of `scenario`, whose summary is `report`.
    #[must_use]
    pub fn figure(&self, scenario: &Scenario, report: &Report) -> Figure {
        let mut events = Vec::new();
        if let Some((from, to)) = scenario.cut_s {
            events.push(Event::new(from, "path cut"));
            events.push(Event::new(to, "path back"));
        }
        if report.failsafe_at_s > 0.0 {
            events.push(Event::new(report.failsafe_at_s, "failsafe"));
        }
        if report.recovered_at_s > 0.0 {
            events.push(Event::new(report.recovered_at_s, "recovered"));
        }
        let with_events = |mut p: Panel| {
            for e in &events {
                p = p.event(e.clone());
            }
            p
        };
        let lq = Panel::new("Link quality (per 1 s status sample)", "LQ (%)")
            .series(Series::new(
                "uplink (at flight side)",
                self.series(|s| Some(f64::from(s.link.uplink_lq))),
            ))
            .series(Series::new(
                "downlink (at module)",
                self.series(|s| Some(f64::from(s.link.downlink_lq))),
            ))
            .y_range(0.0, 105.0);
        let rssi = Panel::new("Signal strength", "RSSI (dBm)")
            .series(Series::new(
                "at flight side",
                self.series(|s| s.link.follower_rssi_dbm.map(f64::from)),
            ))
            .series(Series::new(
                "at module",
                self.series(|s| s.link.master_rssi_dbm.map(f64::from)),
            ));
        let updates = Panel::new("Channel updates delivered", "updates (1/s)").series(Series::new(
            "updates/s",
            self.series(|s| Some(s.update_rate_hz)),
        ));
        let latency = Panel::new("Latency handset sample → flight output", "latency (ms)").series(
            Series::new(
                "mean over the second",
                // No update in a second (a cut) has no latency, not a zero one.
                self.series(|s| (s.update_rate_hz > 0.0).then_some(s.latency_us / 1000.0)),
            ),
        );
        let title = format!(
            "TauLink {} at {} m, {:.0} % extra loss, seed {}",
            report.rate,
            scenario.distance_m,
            scenario.loss * 100.0,
            scenario.seed
        );
        Figure::new(title)
            .x_label("virtual time (s)")
            .panel(with_events(lq))
            .panel(with_events(rssi))
            .panel(with_events(updates))
            .panel(with_events(latency))
    }
}
