//! The end-of-run summary: figures computed from the records, printed as a table or JSON
//! (the JSON derived from the struct: its fields, in their order, are the README's keys).

use std::fmt::Write;

use serde::Serialize;

use crate::json::decimals;

use crate::scenario::Scenario;
use crate::world::Outcome;

/// Figures of one run. Serialized in field order; the attack figures (the last five) only
/// with `--attack` (see [`Report::to_json`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Report {
    /// Rate mode name.
    pub rate: String,
    /// Telemetry ratio.
    pub telemetry_ratio: u8,
    /// Channels the link carries.
    pub channels: usize,
    /// What fed the module (`--handset`).
    pub handset: String,
    /// Air bit rate.
    pub bit_rate_bps: u32,
    /// Slots per second.
    pub slot_rate_hz: u32,
    /// Airtime of a full uplink frame, µs.
    pub uplink_airtime_us: u32,
    /// Virtual seconds simulated.
    #[serde(serialize_with = "decimals::<3, _>")]
    pub duration_s: f64,
    /// Injected loss.
    #[serde(serialize_with = "decimals::<3, _>")]
    pub loss: f64,
    /// Seconds from start until the follower was bound (bind mode) or started.
    #[serde(serialize_with = "decimals::<3, _>")]
    pub bound_s: f64,
    /// Channel updates delivered per second (after the first one).
    #[serde(serialize_with = "decimals::<1, _>")]
    pub update_rate_hz: f64,
    /// Mean uplink latency input → output, ms.
    #[serde(serialize_with = "decimals::<3, _>")]
    pub latency_mean_ms: f64,
    /// 99th percentile uplink latency, ms.
    #[serde(serialize_with = "decimals::<3, _>")]
    pub latency_p99_ms: f64,
    /// Updates per second of the least updated stick (channels 1–4) at the flight side.
    #[serde(serialize_with = "decimals::<1, _>")]
    pub stick_updates_per_s: f64,
    /// Updates per second of the least updated of all channels the link carries.
    #[serde(serialize_with = "decimals::<1, _>")]
    pub all_channel_updates_per_s: f64,
    /// Timing frames the handset followed (crsf-synced).
    pub handset_corrections: u32,
    /// PPM: the share of frames the module's decoder released at their last channel's
    /// closing edge (they agreed with the frame before), %; the others waited for their sync
    /// gap. 0 for the other handsets.
    #[serde(serialize_with = "decimals::<1, _>")]
    pub ppm_early_release_pct: f64,
    /// Uplink LQ at the end (follower).
    pub uplink_lq: u8,
    /// Downlink LQ at the end (master).
    pub downlink_lq: u8,
    /// Mean uplink LQ over the run.
    #[serde(serialize_with = "decimals::<1, _>")]
    pub uplink_lq_mean: f64,
    /// Mean downlink LQ over the run.
    #[serde(serialize_with = "decimals::<1, _>")]
    pub downlink_lq_mean: f64,
    /// RSSI at the follower, dBm.
    pub follower_rssi_dbm: i16,
    /// RSSI at the master, dBm.
    pub master_rssi_dbm: i16,
    /// Uplink stream goodput, B/s.
    #[serde(serialize_with = "decimals::<1, _>")]
    pub uplink_goodput_bps: f64,
    /// Downlink stream goodput, B/s.
    #[serde(serialize_with = "decimals::<1, _>")]
    pub downlink_goodput_bps: f64,
    /// Outputs / stream bytes that were wrong, PPM frames the module dropped (must be 0).
    pub errors: u64,
    /// Failsafe entries.
    pub failsafes: usize,
    /// Time of the first failsafe entry after the link came up, s (0 if none).
    #[serde(serialize_with = "decimals::<4, _>")]
    pub failsafe_at_s: f64,
    /// Time the link left that failsafe, s (0 if it did not).
    #[serde(serialize_with = "decimals::<4, _>")]
    pub recovered_at_s: f64,
    /// Resyncs.
    pub resyncs: u32,
    /// Packets on air.
    pub transmitted: u64,
    /// Packets dropped by the chip header check.
    pub header_rejected: u64,
    /// Packets dropped by the chip CRC.
    pub chip_crc_rejected: u64,
    /// Packets rejected by the link decoders.
    pub link_rejected: u64,
    /// Wrong outputs or bytes on the foreign link (must be 0).
    pub foreign_errors: u64,
    /// The attack run (`--attack`), if any.
    #[serde(skip)]
    pub attack: Option<String>,
    /// Frames the attacking radio sent.
    #[serde(skip)]
    pub attacker_frames_sent: u64,
    /// Attacker frames a victim's link core accepted (must be 0).
    #[serde(skip)]
    pub attacker_frames_accepted: u64,
    /// Times the flight side was power-cycled.
    #[serde(skip)]
    pub power_cycles: u32,
    /// Boots after which the flight side ran a link other than the module's (must be 0).
    #[serde(skip)]
    pub rebinds: u32,
    /// Epochs the master adopted (each an uplink spent on its nonce).
    #[serde(skip)]
    pub handshakes_adopted: u32,
    /// Verified nonce frames the master refused (replays, or more than one a wrap).
    #[serde(skip)]
    pub nonce_frames_refused: u32,
    /// Tag failures counted by the module and by the flight side.
    #[serde(skip)]
    pub tag_failures: (u32, u32),
    /// `--attack guess`: what the guesser recorded and found.
    #[serde(skip)]
    pub guess: Option<crate::attack::GuessFigures>,
}

fn percentile(sorted: &[u32], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted.get(i).map_or(0.0, |&v| f64::from(v))
}

/// Summarises an outcome.
pub fn summarise(s: &Scenario, o: &Outcome) -> Report {
    let m = &o.main;
    let mut lat = m.latencies_us.clone();
    lat.sort_unstable();
    let bound_us = m.bound_us.unwrap_or(0);
    let active_s = (s.duration_s - bound_us as f64 / 1e6).max(1e-6);
    let mean = if lat.is_empty() {
        0.0
    } else {
        lat.iter().map(|&v| f64::from(v)).sum::<f64>() / lat.len() as f64
    };
    let frame = telemetry::frame::uplink_overhead(s.format, false);
    let per_s = |n: u64| n as f64 / active_s;
    let carried = m.channel_updates.iter().take(s.format.count());
    Report {
        rate: format!("{:?}", s.rate),
        telemetry_ratio: s.telemetry_ratio,
        channels: s.format.count(),
        handset: s.handset.name().to_string(),
        bit_rate_bps: s.rate.bit_rate_bps(),
        slot_rate_hz: s.rate.slot_rate_hz(),
        uplink_airtime_us: s.rate.airtime_us(frame),
        duration_s: s.duration_s,
        loss: s.loss,
        bound_s: bound_us as f64 / 1e6,
        update_rate_hz: m.outputs_ok as f64 / active_s,
        latency_mean_ms: mean / 1000.0,
        latency_p99_ms: percentile(&lat, 0.99) / 1000.0,
        stick_updates_per_s: per_s(m.channel_updates.iter().take(4).copied().min().unwrap_or(0)),
        all_channel_updates_per_s: per_s(carried.copied().min().unwrap_or(0)),
        handset_corrections: m.handset_corrections,
        ppm_early_release_pct: match m.input_released {
            (0, _) => 0.0,
            (all, early) => 100.0 * f64::from(early) / f64::from(all),
        },
        uplink_lq: m.now.uplink_lq,
        uplink_lq_mean: m.uplink_lq_mean(),
        downlink_lq_mean: m.downlink_lq_mean(),
        downlink_lq: m.now.downlink_lq,
        follower_rssi_dbm: m.now.follower_rssi_dbm.unwrap_or(0),
        master_rssi_dbm: m.now.master_rssi_dbm.unwrap_or(0),
        uplink_goodput_bps: m.up_bytes_ok as f64 / active_s,
        downlink_goodput_bps: m.down_bytes_ok as f64 / active_s,
        errors: m.outputs_bad + m.up_bytes_bad + m.down_bytes_bad + u64::from(m.input_rejected),
        failsafes: m
            .failsafe_changes
            .iter()
            .filter(|(_, entering)| *entering)
            .count(),
        failsafe_at_s: m
            .failsafe_changes
            .iter()
            .find(|c| c.1)
            .map_or(0.0, |c| c.0 as f64 / 1e6),
        recovered_at_s: m
            .failsafe_changes
            .iter()
            .skip_while(|c| !c.1)
            .find(|c| !c.1)
            .map_or(0.0, |c| c.0 as f64 / 1e6),
        resyncs: m.now.resyncs,
        transmitted: o.medium.transmitted,
        header_rejected: o.medium.header_rejected,
        chip_crc_rejected: o.medium.chip_crc_rejected,
        link_rejected: u64::from(m.now.follower_rejected) + u64::from(m.now.master_rejected),
        foreign_errors: o
            .foreign
            .as_ref()
            .map_or(0, |f| f.outputs_bad + f.up_bytes_bad + f.down_bytes_bad),
        attack: s.attack.map(|a| a.name().to_string()),
        attacker_frames_sent: m.attacker_sent,
        attacker_frames_accepted: m.attacker_accepted,
        power_cycles: m.power_cycles,
        rebinds: m.rebinds,
        handshakes_adopted: m.handshakes.0,
        nonce_frames_refused: m.handshakes.1,
        tag_failures: m.tag_failures,
        guess: m.guess,
    }
}

impl Report {
    /// Whether the run went wrong: a wrong output or stream byte, an attack that got
    /// anything accepted, or a recording that lets a phrase be checked offline.
    pub fn failed(&self) -> bool {
        self.errors > 0
            || self.foreign_errors > 0
            || self.attacker_frames_accepted > 0
            || self.rebinds > 0
            || self.guess.is_some_and(|g| g.verdict.offline_checkable)
    }

    /// One JSON object: every field, the attack figures only if there was an attack.
    pub fn to_json(&self) -> String {
        crate::json::to_string(&Json {
            report: self,
            attack: self.attack.as_deref().map(|attack| AttackJson {
                attack,
                attacker_frames_sent: self.attacker_frames_sent,
                attacker_frames_accepted: self.attacker_frames_accepted,
                power_cycles: self.power_cycles,
                rebinds: self.rebinds,
                handshakes_adopted: self.handshakes_adopted,
                nonce_frames_refused: self.nonce_frames_refused,
                tag_failures_module: self.tag_failures.0,
                tag_failures_flight: self.tag_failures.1,
                guess: self.guess.map(|g| GuessJson {
                    recorded_bind_frames: g.bind_frames,
                    recorded_link_frames: g.link_frames,
                    recorded_nonce_frames: g.nonce_frames,
                    guesses: g.verdict.guesses,
                    checks: g.verdict.checks,
                    offline_checkable: g.verdict.offline_checkable,
                }),
            }),
        })
    }

    /// The human-readable summary.
    pub fn table(&self) -> String {
        let mut t = String::new();
        let mut row = |k: &str, v: String| {
            let _ = writeln!(t, "  {k:<28} {v}");
        };
        row(
            "rate mode",
            format!(
                "{} ({} bps, {} Hz slots, 1:{} telemetry, {} ch)",
                self.rate,
                self.bit_rate_bps,
                self.slot_rate_hz,
                self.telemetry_ratio,
                self.channels
            ),
        );
        row("uplink airtime", format!("{} µs", self.uplink_airtime_us));
        row("bound after", format!("{:.3} s", self.bound_s));
        row("channel updates", format!("{:.1} /s", self.update_rate_hz));
        row(
            "sticks / every channel",
            format!(
                "{:.1} / {:.1} updates/s",
                self.stick_updates_per_s, self.all_channel_updates_per_s
            ),
        );
        row(
            &format!("latency ({})", self.handset),
            format!(
                "mean {:.2} ms, p99 {:.2} ms",
                self.latency_mean_ms, self.latency_p99_ms
            ),
        );
        if self.handset == "ppm" {
            row(
                "PPM released early",
                format!("{:.1} % of frames", self.ppm_early_release_pct),
            );
        }
        row(
            "LQ up / down",
            format!("{} % / {} %", self.uplink_lq, self.downlink_lq),
        );
        row(
            "RSSI follower / master",
            format!("{} / {} dBm", self.follower_rssi_dbm, self.master_rssi_dbm),
        );
        row(
            "telemetry goodput up / down",
            format!(
                "{:.0} / {:.0} B/s",
                self.uplink_goodput_bps, self.downlink_goodput_bps
            ),
        );
        row(
            "failsafes / resyncs",
            format!("{} / {}", self.failsafes, self.resyncs),
        );
        row("packets on air", self.transmitted.to_string());
        row(
            "rejected hdr / chip CRC / link",
            format!(
                "{} / {} / {}",
                self.header_rejected, self.chip_crc_rejected, self.link_rejected
            ),
        );
        row(
            "errors (must be 0)",
            format!("{} (foreign link: {})", self.errors, self.foreign_errors),
        );
        if let Some(attack) = &self.attack {
            row(
                &format!("attack {attack}: frames sent"),
                self.attacker_frames_sent.to_string(),
            );
            row(
                "accepted / rebinds (must be 0)",
                format!(
                    "{} / {} ({} flight power cycles)",
                    self.attacker_frames_accepted, self.rebinds, self.power_cycles
                ),
            );
            row(
                "epochs adopted / refused",
                format!(
                    "{} / {} nonce frames",
                    self.handshakes_adopted, self.nonce_frames_refused
                ),
            );
            row(
                "tag failures module / flight",
                format!("{} / {}", self.tag_failures.0, self.tag_failures.1),
            );
            if let Some(g) = self.guess {
                row(
                    "recorded bind / link frames",
                    format!(
                        "{} / {} ({} with a nonce)",
                        g.bind_frames, g.link_frames, g.nonce_frames
                    ),
                );
                row(
                    "offline checkable (must not)",
                    format!(
                        "{} ({} words × {} checks)",
                        g.verdict.offline_checkable, g.verdict.guesses, g.verdict.checks
                    ),
                );
            }
        }
        t
    }
}

/// The JSON of a report: its fields, then the attack's (present only with `--attack`).
#[derive(Serialize)]
struct Json<'a> {
    #[serde(flatten)]
    report: &'a Report,
    #[serde(flatten)]
    attack: Option<AttackJson<'a>>,
}

/// The attack figures of [`Report`], in their JSON order.
#[derive(Serialize)]
struct AttackJson<'a> {
    attack: &'a str,
    attacker_frames_sent: u64,
    attacker_frames_accepted: u64,
    power_cycles: u32,
    rebinds: u32,
    handshakes_adopted: u32,
    nonce_frames_refused: u32,
    tag_failures_module: u32,
    tag_failures_flight: u32,
    #[serde(flatten)]
    guess: Option<GuessJson>,
}

/// The guesser's figures (`--attack guess` only), in their JSON order.
#[derive(Serialize)]
struct GuessJson {
    recorded_bind_frames: u32,
    recorded_link_frames: u32,
    recorded_nonce_frames: u32,
    guesses: u32,
    checks: u32,
    offline_checkable: bool,
}
