//! `cargo run --release -p taulink-sim -- [options]`: runs both link ends for a virtual
//! duration and prints a live status line and a summary (or JSON). `--help` lists the
//! options (`cli.rs`).

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;
use sim_plot::docblock;
use taulink_sim::{Cli, Report, Scenario, Status, run};

fn status_line(st: &Status) {
    let l = &st.link;
    let rssi = |r: Option<i16>| r.map_or("  --".into(), |v| format!("{v:4}"));
    eprint!(
        "\r{:6.1} s  LQ up {:3}% dn {:3}%  RSSI fl {} ms {} dBm  {:6.1} upd/s  lat {:5.2} ms  ch {:4} {:4} {:4} {:4}  tlm {:6.0}/{:6.0} B/s  {}",
        st.time_s,
        l.uplink_lq,
        l.downlink_lq,
        rssi(l.follower_rssi_dbm),
        rssi(l.master_rssi_dbm),
        st.update_rate_hz,
        st.latency_us / 1000.0,
        l.channels[0],
        l.channels[1],
        l.channels[2],
        l.channels[3],
        st.goodput_bps.0,
        st.goodput_bps.1,
        if l.failsafe {
            "FAILSAFE"
        } else if l.tracking {
            "tracking"
        } else {
            "acquiring"
        },
    );
    let _ = std::io::stderr().flush();
}

/// The sweep's runs: every rate mode, clean and at 10 % loss, with a progress bar over the
/// virtual seconds of all runs when `progress` is on.
fn sweep(base: &Scenario, progress: bool) -> Vec<(Report, Report)> {
    let modes = telemetry::link::RateMode::ALL;
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)] // ≤ 86400 s each
    let per_run = base.duration_s.ceil() as u64;
    let total = per_run * 2 * modes.len() as u64;
    let bar = sim_plot::progress::bar(total, "virtual s", progress);
    let mut reports: Vec<(Report, Report)> = Vec::new();
    let mut done = 0;
    for mode in modes {
        let s = taulink_sim::sweep::scenario(base, mode);
        let mut one = |loss: f64| {
            bar.set_message(format!("{mode:?} loss {:.0} %", loss * 100.0));
            #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
            let r = run(&Scenario { loss, ..s.clone() }, |st| {
                bar.set_position(done + st.time_s as u64);
            });
            done += per_run;
            r
        };
        let clean = one(0.0);
        let lossy = one(0.1);
        reports.push((clean, lossy));
    }
    bar.finish_and_clear();
    reports
}

fn print_sweep(reports: &[(Report, Report)], json: bool) {
    if json {
        let items: Vec<String> = reports
            .iter()
            .map(|(c, l)| {
                format!(
                    "{{\"clean\": {}, \"loss10\": {}}}",
                    c.to_json(),
                    l.to_json()
                )
            })
            .collect();
        println!("[{}]", items.join(",\n "));
        return;
    }
    if let Some((c, _)) = reports.first() {
        println!("handset: {}", c.handset);
    }
    println!(
        "mode  bit rate  slots  ch ratio updates/s  sticks/s  all ch/s  latency mean/p99 ms   mean LQ up/down clean | 10%     goodput up/down B/s clean | 10%"
    );
    for (c, l) in reports {
        println!(
            "{:<5} {:>8}  {:>5}  {:>2}  1:{:<3} {:>8.1}  {:>8.1}  {:>8.1}  {:>8.2} / {:<8.2}  {:>5.1} / {:<5.1} | {:>5.1} / {:<5.1}  {:>5.0} / {:<5.0} | {:>5.0} / {:<5.0}",
            c.rate,
            c.bit_rate_bps,
            c.slot_rate_hz,
            c.channels,
            c.telemetry_ratio,
            c.update_rate_hz,
            c.stick_updates_per_s,
            c.all_channel_updates_per_s,
            c.latency_mean_ms,
            c.latency_p99_ms,
            c.uplink_lq_mean,
            c.downlink_lq_mean,
            l.uplink_lq_mean,
            l.downlink_lq_mean,
            c.uplink_goodput_bps,
            c.downlink_goodput_bps,
            l.uplink_goodput_bps,
            l.downlink_goodput_bps
        );
    }
    println!(
        "OpenLRSng: 40 Hz at 19.2 kbps, 8 ch + 9-byte telemetry reply per packet; ExpressLRS 900 MHz: 200 Hz (LoRa SF6, 1:64 telemetry)"
    );
}

/// `--docs MODE`: the docs' link figures from a fresh set of runs.
fn docs(mode: docblock::Mode, progress: bool) -> ExitCode {
    let modes = telemetry::link::RateMode::ALL.len() as u64;
    let bar = sim_plot::progress::bar(3 * modes, "runs", progress);
    let runs = taulink_sim::docs::run(|name| {
        bar.set_message(name.to_owned());
        bar.inc(1);
    });
    bar.finish_and_clear();
    if taulink_sim::docs::failed(&runs) {
        eprintln!("taulink-sim: a run delivered a wrong output or stream byte");
        return ExitCode::FAILURE;
    }
    let mut stale = false;
    for (doc, name, table) in taulink_sim::docs::blocks(&runs) {
        match docblock::apply(&doc, name, &table, mode) {
            Ok(current) => stale |= !current,
            Err(e) => {
                eprintln!("taulink-sim: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    if stale && mode == docblock::Mode::Check {
        eprintln!(
            "taulink-sim: the docs' link figures are stale: run `cargo run --release -p taulink-sim -- --docs write`"
        );
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}

/// `--dynamic-power --walk`: both walks, the table (or JSON), exit 1 when LQ was lost.
fn walk(plan: &taulink_sim::walk::WalkPlan, json: bool) -> ExitCode {
    let report = taulink_sim::walk::WalkReport::run(plan);
    if json {
        match serde_json::to_string_pretty(&report) {
            Ok(text) => println!("{text}"),
            Err(e) => {
                eprintln!("taulink-sim: {e}");
                return ExitCode::FAILURE;
            }
        }
    } else {
        print!("{}", report.table());
    }
    if report.lq_lost().is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// `--dynamic-power --walk --docs MODE`: the README's `dynamic-power` block from the
/// documented walk.
fn walk_docs(mode: docblock::Mode) -> ExitCode {
    let report = taulink_sim::walk::WalkReport::run(&taulink_sim::walk::WalkPlan::DOCUMENTED);
    let readme = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
    match docblock::apply(&readme, "dynamic-power", &report.table(), mode) {
        Ok(false) if mode == docblock::Mode::Check => {
            eprintln!(
                "taulink-sim: the dynamic-power walk is stale: run `cargo run --release -p taulink-sim -- --dynamic-power --walk --docs write`"
            );
            ExitCode::FAILURE
        }
        Ok(_) if report.lq_lost().is_empty() => ExitCode::SUCCESS,
        Ok(_) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("taulink-sim: {e}");
            ExitCode::FAILURE
        }
    }
}

fn main() -> ExitCode {
    // clap prints --help/--version (exit 0) and usage errors with a suggestion (exit 2).
    let cli = Cli::parse();
    match cli.openlrs() {
        Err(e) => {
            eprintln!("taulink-sim: error: {e}");
            return ExitCode::from(2);
        }
        Ok(Some(olrs)) => {
            let report = taulink_sim::openlrs::run(&olrs);
            if cli.json {
                println!("{}", report.to_json());
            } else {
                println!(
                    "OpenLRSng simulation, {:.1} s virtual, seed {}",
                    olrs.duration_s, olrs.seed
                );
                print!("{}", report.table());
            }
            return if report.failed() {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            };
        }
        Ok(None) => {}
    }
    if let Some(plan) = cli.walk_plan() {
        return match cli.docs {
            Some(mode) => walk_docs(mode.into()),
            None => walk(&plan, cli.json),
        };
    }
    if let Some(options) = taulink_sim::serve::options(&cli) {
        return ExitCode::from(u8::try_from(taulink_sim::serve::main(options)).unwrap_or(1));
    }
    let scenario = cli.scenario();
    let live = sim_plot::progress::wanted(cli.quiet, cli.json);
    if let Some(mode) = cli.docs {
        return docs(mode.into(), live);
    }
    if cli.sweep {
        let reports = sweep(&scenario, live);
        print_sweep(&reports, cli.json);
        let wrong = reports
            .iter()
            .flat_map(|(c, l)| [c, l])
            .any(|r| r.errors > 0 || r.foreign_errors > 0);
        return if wrong {
            ExitCode::FAILURE
        } else {
            ExitCode::SUCCESS
        };
    }
    let mut trace = taulink_sim::plot::Trace::default();
    let report = run(&scenario, |st| {
        if live {
            status_line(st);
        }
        trace.push(st);
    });
    if live {
        eprintln!();
    }
    if cli.json {
        println!("{}", report.to_json());
    } else {
        println!(
            "TauLink simulation, {:.1} s virtual, seed {}",
            scenario.duration_s, scenario.seed
        );
        print!("{}", report.table());
    }
    if let Some(path) = cli.plot.path("link")
        && let Err(e) = trace
            .figure(&scenario, &report)
            .save_as(&path, cli.plot.plot_format)
    {
        eprintln!("taulink-sim: plot {}: {e}", path.display());
        return ExitCode::FAILURE;
    }
    if report.failed() {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}
