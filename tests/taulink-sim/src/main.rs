//! `cargo run --release -p taulink-sim -- [options]`: runs both link ends for a virtual
//! duration and prints a live status line and a summary (or JSON).

use std::io::Write;

use taulink_sim::scenario::parse_rate;
use taulink_sim::{Report, Scenario, Status, parse_args, run};

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

fn sweep(base: &Scenario, json: bool) {
    let mut reports: Vec<(Report, Report)> = Vec::new();
    for name in ["L50", "M100", "F250", "F500"] {
        let mut s = base.clone();
        s.rate = parse_rate(name).unwrap_or(s.rate);
        // The long-range mode carries 8 channels (as OpenLRSng does at that rate) to leave
        // room for uplink telemetry; the others carry 16.
        if s.rate == telemetry::link::RateMode::L50 {
            s.format = telemetry::channels::ChannelFormat::Compact8;
        }
        let clean = run(
            &Scenario {
                loss: 0.0,
                ..s.clone()
            },
            |_| {},
        );
        let lossy = run(&Scenario { loss: 0.1, ..s }, |_| {});
        reports.push((clean, lossy));
    }
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
    println!(
        "mode  bit rate  slots  ch  updates/s  latency mean/p99 ms   mean LQ up/down clean | 10%     goodput up/down B/s clean | 10%"
    );
    for (c, l) in &reports {
        println!(
            "{:<5} {:>8}  {:>5}  {:>2}  {:>9.1}  {:>8.2} / {:<8.2}  {:>5.1} / {:<5.1} | {:>5.1} / {:<5.1}  {:>5.0} / {:<5.0} | {:>5.0} / {:<5.0}",
            c.rate,
            c.bit_rate_bps,
            c.slot_rate_hz,
            c.channels,
            c.update_rate_hz,
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

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Some(("--serve", rest)) = args.split_first().map(|(a, r)| (a.as_str(), r)) {
        std::process::exit(taulink_sim::serve::main(rest));
    }
    let (scenario, output) = match parse_args(&args) {
        Ok(v) => v,
        Err(msg) => {
            eprintln!("{msg}");
            std::process::exit(2);
        }
    };
    if output.sweep {
        sweep(&scenario, output.json);
        return;
    }
    let live = !output.quiet && !output.json;
    let report = run(&scenario, |st| {
        if live {
            status_line(st);
        }
    });
    if live {
        eprintln!();
    }
    if output.json {
        println!("{}", report.to_json());
    } else {
        println!(
            "TauLink simulation, {:.1} s virtual, seed {}",
            scenario.duration_s, scenario.seed
        );
        print!("{}", report.table());
    }
    if report.errors > 0 || report.foreign_errors > 0 {
        std::process::exit(1);
    }
}
