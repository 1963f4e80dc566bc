//! The link figures the docs quote as current, generated (`taulink-sim --docs
//! print|check|write`): the top README's "Link figures" table and the protocol spec's §10
//! table, each between `<!-- link-figures…` markers ([`sim_plot::docblock`]). One set of
//! runs feeds both: every rate mode at the documented conditions ([`Scenario::default`]:
//! chip level, 30 s, 500 m, 433 MHz, seed 1, 1:4 telemetry, F700 1:8) fed by the
//! `crsf-synced` handset clean and at 10 % loss, and by free-running `ppm` clean.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use telemetry::link::RateMode;

use crate::handset::HandsetKind;
use crate::report::Report;
use crate::scenario::Scenario;
use crate::{sweep, world};

/// One rate mode's runs.
#[derive(Clone, Debug, Default)]
pub struct ModeRuns {
    /// EdgeTX on CRSF following the timing frames, no injected loss.
    pub synced: Report,
    /// The same at 10 % injected loss.
    pub synced_loss10: Report,
    /// Free-running PPM, no injected loss.
    pub ppm: Report,
}

/// The scenarios of one mode's runs, in [`ModeRuns`] order.
#[must_use]
pub fn scenarios(mode: RateMode) -> [Scenario; 3] {
    let s = sweep::scenario(&Scenario::default(), mode);
    [
        s.clone(),
        Scenario {
            loss: 0.1,
            ..s.clone()
        },
        Scenario {
            handset: HandsetKind::Ppm,
            ..s
        },
    ]
}

/// Every mode's runs; `progress` is told each finished run.
pub fn run(mut progress: impl FnMut(&str)) -> Vec<ModeRuns> {
    RateMode::ALL
        .into_iter()
        .map(|mode| {
            let [a, b, c] = scenarios(mode).map(|s| {
                let r = world::run(&s, |_| {});
                progress(&format!(
                    "{mode:?} {} loss {:.0} %",
                    r.handset,
                    s.loss * 100.0
                ));
                r
            });
            ModeRuns {
                synced: a,
                synced_loss10: b,
                ppm: c,
            }
        })
        .collect()
}

/// Whether any run delivered a wrong output or stream byte.
#[must_use]
pub fn failed(runs: &[ModeRuns]) -> bool {
    runs.iter()
        .flat_map(|m| [&m.synced, &m.synced_loss10, &m.ppm])
        .any(Report::failed)
}

/// A whole number with thousands grouped by a space ("1 802"), the project's format.
#[must_use]
pub fn grouped(v: f64) -> String {
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)] // B/s, ≥ 0, < 2^53
    let digits = (v.max(0.0).round() as u64).to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

/// "L50 (19.2 kbps, 8 ch, 1:4)".
fn mode_name(r: &Report) -> String {
    format!(
        "{} ({} kbps, {} ch, 1:{})",
        r.rate,
        f64::from(r.bit_rate_bps) / 1000.0,
        r.channels,
        r.telemetry_ratio
    )
}

/// The top README's table.
#[must_use]
pub fn readme_table(runs: &[ModeRuns]) -> String {
    let mut t = String::from(
        "| mode | sticks / every channel, updates/s | latency p99, EdgeTX CRSF synced | latency p99, free-running PPM | telemetry up / down |\n|---|---|---|---|---|\n",
    );
    for m in runs {
        let (s, p) = (&m.synced, &m.ppm);
        let _ = writeln!(
            t,
            "| {} | {:.1} / {:.1} | {:.2} ms | {:.2} ms | {} / {} B/s |",
            mode_name(s),
            s.stick_updates_per_s,
            s.all_channel_updates_per_s,
            s.latency_p99_ms,
            p.latency_p99_ms,
            grouped(s.uplink_goodput_bps),
            grouped(s.downlink_goodput_bps),
        );
    }
    t
}

/// The spec's §10 table.
#[must_use]
pub fn spec_table(runs: &[ModeRuns]) -> String {
    let mut t = String::from(
        "| mode | updates/s: sticks / every channel | latency mean / p99 (ms): crsf-synced | ppm | mean LQ up / down: clean | at 10 % loss | goodput up / down (B/s): clean | at 10 % loss |\n|---|---|---|---|---|---|---|---|\n",
    );
    for m in runs {
        let (s, l, p) = (&m.synced, &m.synced_loss10, &m.ppm);
        let _ = writeln!(
            t,
            "| {} | {:.1} / {:.1} | {:.2} / {:.2} | {:.2} / {:.2} | {:.1} / {:.1} | {:.1} / {:.1} | {} / {} | {} / {} |",
            mode_name(s),
            s.stick_updates_per_s,
            s.all_channel_updates_per_s,
            s.latency_mean_ms,
            s.latency_p99_ms,
            p.latency_mean_ms,
            p.latency_p99_ms,
            s.uplink_lq_mean,
            s.downlink_lq_mean,
            l.uplink_lq_mean,
            l.downlink_lq_mean,
            grouped(s.uplink_goodput_bps),
            grouped(s.downlink_goodput_bps),
            grouped(l.uplink_goodput_bps),
            grouped(l.downlink_goodput_bps),
        );
    }
    t
}

/// The documents and their blocks: (path from the workspace root, block name, table).
#[must_use]
pub fn blocks(runs: &[ModeRuns]) -> [(PathBuf, &'static str, String); 2] {
    // tests/taulink-sim → the workspace root.
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let root = manifest.ancestors().nth(2).unwrap_or(manifest);
    [
        (root.join("README.md"), "link-figures", readme_table(runs)),
        (
            root.join("telemetry/spec/protocol.md"),
            "link-figures",
            spec_table(runs),
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(rate: &str, up: f64) -> Report {
        Report {
            rate: rate.into(),
            bit_rate_bps: 19_200,
            channels: 8,
            telemetry_ratio: 4,
            stick_updates_per_s: 36.66,
            all_channel_updates_per_s: 36.66,
            latency_mean_ms: 25.5,
            latency_p99_ms: 40.519,
            uplink_goodput_bps: up,
            downlink_goodput_bps: 281.2,
            uplink_lq_mean: 100.0,
            downlink_lq_mean: 100.0,
            ..Report::default()
        }
    }

    #[test]
    fn numbers_are_grouped_by_spaces() {
        assert_eq!(grouped(7.4), "7");
        assert_eq!(grouped(1801.6), "1 802");
        assert_eq!(grouped(1_000_000.0), "1 000 000");
    }

    #[test]
    fn the_readme_row_takes_the_p99_of_both_handsets() {
        let runs = [ModeRuns {
            synced: report("L50", 488.0),
            synced_loss10: report("L50", 374.0),
            ppm: Report {
                latency_p99_ms: 58.5,
                ..report("L50", 0.0)
            },
        }];
        let t = readme_table(&runs);
        assert_eq!(
            t.lines().nth(2),
            Some(
                "| L50 (19.2 kbps, 8 ch, 1:4) | 36.7 / 36.7 | 40.52 ms | 58.50 ms | 488 / 281 B/s |"
            )
        );
        let s = spec_table(&runs);
        assert_eq!(
            s.lines().nth(2),
            Some(
                "| L50 (19.2 kbps, 8 ch, 1:4) | 36.7 / 36.7 | 25.50 / 40.52 | 25.50 / 58.50 | 100.0 / 100.0 | 100.0 / 100.0 | 488 / 281 | 374 / 281 |"
            )
        );
    }

    #[test]
    fn every_mode_runs_synced_clean_and_lossy_and_ppm_clean() {
        for mode in RateMode::ALL {
            let [a, b, c] = scenarios(mode);
            assert_eq!((a.loss, b.loss, c.loss), (0.0, 0.1, 0.0));
            assert_eq!(a.handset, HandsetKind::CrsfSynced);
            assert_eq!(b.handset, HandsetKind::CrsfSynced);
            assert_eq!(c.handset, HandsetKind::Ppm);
            assert!(a.chip_level && a.duration_s == 30.0 && a.seed == 1);
        }
    }
}
