//! `--protocol openlrs38|openlrs39`: the crate's OpenLRSng TX role flying its RX role
//! (`openlrs::roles`, the state machines and register scripts the firmware
//! runs) on two virtual Si4432s, with the figures the TauLink report has: channel updates/s,
//! latency (handset value change → receiver output), LQ both ways, failsafe and recovery
//! time after a cut. The ends bind over the air first, as a fresh pair would.

use core::cell::RefCell;
use core::time::Duration;
use std::rc::Rc;

use openlrs::modem::PROFILES;
use openlrs::radio::Radio;
use openlrs::roles::{RxEvent, rx_start, rx_step, tx_bind, tx_start, tx_step};
use openlrs::rx::{Config, Receiver};
use openlrs::tx::Transmitter;
use openlrs::{BindData, BindingVersion, timing};
use radio_rfm22b::RfmType;
use serde::Serialize;
use si4432_sim::{Medium, Outcome, RadioConfig, RadioHandle, RadioId, Simulation};

use crate::json::{decimals, decimals_or_null};

/// The virtual chips' power-on reset time, waited before the first register access.
const POWER_UP_US: u32 = 30_000;
/// How long the TX offers the bind before giving up.
const BIND_WINDOW_US: u64 = 3_000_000;
/// The handset moves channel 1 to a new value this often (faster than any OpenLRSng
/// interval, so every packet carries a fresh value and latency includes the wait for it).
const STEP_US: u64 = 2_000;
/// Channel values are 10 bits: channel 1 carries the step number modulo this.
const WRAP: u64 = 1024;

/// What an OpenLRSng run simulates.
#[derive(Clone, Debug, PartialEq)]
pub struct OpenLrsScenario {
    /// Binding version of both ends (3.8 or 3.9).
    pub version: BindingVersion,
    /// Modem profile 0..=4 (4800, 9600, 19200, 57600, 125000 bit/s).
    pub modem_profile: u8,
    /// 16 channels instead of 8.
    pub sixteen_channels: bool,
    /// Distance between the ends, metres.
    pub distance_m: f64,
    /// Extra random packet loss, 0..=1.
    pub loss: f64,
    /// Seed of the medium's random choices.
    pub seed: u64,
    /// Virtual duration, seconds.
    pub duration_s: f64,
    /// Path cut from..to, seconds.
    pub cut_s: Option<(f64, f64)>,
}

impl Default for OpenLrsScenario {
    fn default() -> Self {
        Self {
            version: BindingVersion::V38,
            modem_profile: 2,
            sixteen_channels: false,
            distance_m: 500.0,
            loss: 0.0,
            seed: 1,
            duration_s: 30.0,
            cut_s: None,
        }
    }
}

/// The figures of one OpenLRSng run; serialized in field order (the README's JSON keys).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OpenLrsReport {
    /// "openlrs38" or "openlrs39".
    pub protocol: &'static str,
    /// Air bit rate of the modem profile.
    pub bit_rate_bps: u32,
    /// Uplink packet interval (OpenLRSng's `getInterval`).
    pub interval_us: u32,
    /// Channels per packet.
    pub channels: usize,
    /// Whether the bind succeeded.
    pub bound: bool,
    /// Channel updates delivered per second of link time (after the first, outside the cut).
    #[serde(serialize_with = "decimals::<3, _>")]
    pub update_rate_hz: f64,
    /// Mean latency from the handset's value change to the receiver's output, ms.
    #[serde(serialize_with = "decimals::<3, _>")]
    pub latency_mean_ms: f64,
    /// 99th percentile of that latency, ms.
    #[serde(serialize_with = "decimals::<3, _>")]
    pub latency_p99_ms: f64,
    /// Uplink packets received intact, percent of those sent (link time outside the cut).
    #[serde(rename = "uplink_lq_mean", serialize_with = "decimals::<2, _>")]
    pub uplink_lq_pct: f64,
    /// Telemetry replies received intact by the TX, percent of those sent.
    #[serde(rename = "downlink_lq_mean", serialize_with = "decimals::<2, _>")]
    pub downlink_lq_pct: f64,
    /// From the cut's start to the receiver's failsafe, ms.
    #[serde(serialize_with = "decimals_or_null::<3, _>")]
    pub failsafe_ms: Option<f64>,
    /// From the cut's end to the next channel update, ms.
    #[serde(serialize_with = "decimals_or_null::<3, _>")]
    pub recovery_ms: Option<f64>,
    /// Channel outputs that were not a value the handset set (must be 0).
    pub errors: u64,
}

impl OpenLrsReport {
    /// Whether anything went wrong (no bind or a wrong channel value).
    #[must_use]
    pub fn failed(&self) -> bool {
        !self.bound || self.errors > 0
    }

    /// The report as one JSON object.
    #[must_use]
    pub fn to_json(&self) -> String {
        crate::json::to_string(self)
    }

    /// The report as a human-readable table.
    #[must_use]
    pub fn table(&self) -> String {
        let opt = |v: Option<f64>| v.map_or("--".into(), |v| format!("{v:.1} ms"));
        format!(
            "protocol          {}\nbit rate          {} bit/s\ninterval          {} us\nchannels          {}\nbound             {}\nupdates/s         {:.1}\nlatency mean/p99  {:.2} / {:.2} ms\nLQ up / down      {:.1} / {:.1} %\nfailsafe after    {}\nrecovery after    {}\nwrong outputs     {}\n",
            self.protocol,
            self.bit_rate_bps,
            self.interval_us,
            self.channels,
            self.bound,
            self.update_rate_hz,
            self.latency_mean_ms,
            self.latency_p99_ms,
            self.uplink_lq_pct,
            self.downlink_lq_pct,
            opt(self.failsafe_ms),
            opt(self.recovery_ms),
            self.errors
        )
    }
}

type SimRadio =
    Radio<si4432_sim::SimSpi, si4432_sim::SimIrq, si4432_sim::SimDelay, Box<dyn FnMut() -> u64>>;

fn now_us(medium: &Medium) -> u64 {
    u64::try_from(medium.now().as_micros()).unwrap_or(u64::MAX)
}

fn radio(handle: RadioHandle, medium: &Medium, version: BindingVersion) -> SimRadio {
    let m = medium.clone();
    let clock: Box<dyn FnMut() -> u64> = Box::new(move || now_us(&m));
    Radio::new(
        handle.spi,
        handle.nirq,
        handle.delay,
        clock,
        version,
        RfmType::Mhz433,
    )
}

/// The channel values the handset holds at `t_us`: channel 1 counts steps, the rest fixed.
fn handset(t_us: u64, count: usize) -> Vec<u16> {
    let step = u16::try_from((t_us / STEP_US) % WRAP).unwrap_or(0);
    core::iter::once(step).chain(fixed(count)).collect()
}

/// Channels 2.. : fixed values spread over the 10-bit range.
fn fixed(count: usize) -> impl Iterator<Item = u16> {
    (1..count).map(|i| u16::try_from(12 + 66 * i).unwrap_or(0))
}

#[derive(Default)]
struct Log {
    /// (output time, values).
    outputs: Vec<(u64, Vec<u16>)>,
    failsafe_at_us: Vec<u64>,
    bound_at_us: Option<u64>,
    tx_bound: Option<bool>,
}

fn us(s: f64) -> u64 {
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)] // ≤ 86400 s
    let v = (s * 1e6).round() as u64;
    v
}

/// Runs the scenario and summarises it.
#[must_use]
pub fn run(s: &OpenLrsScenario) -> OpenLrsReport {
    let mut data = BindData::defaults(s.version, RfmType::Mhz433);
    data.rf_magic = 0x1234_5678 ^ u32::try_from(s.seed & 0xFFFF).unwrap_or(0);
    data.modem_profile = s.modem_profile;
    // 8 channels + passthrough telemetry (the default) or 16 channels + telemetry.
    data.flags = if s.sixteen_channels { 0x0E } else { 0x0A };
    let count = if s.sixteen_channels { 16 } else { 8 };
    let interval = timing::interval_us(&data).unwrap_or(0);
    let bit_rate_bps = PROFILES
        .get(usize::from(s.modem_profile))
        .map_or(0, |p| p.bps);

    let sim = Simulation::new(s.seed);
    let medium = sim.medium();
    medium.set_packet_loss(s.loss);
    let tx_handle = medium.add_radio(RadioConfig::at([0.0, 0.0, 0.0]));
    let rx_handle = medium.add_radio(RadioConfig::at([s.distance_m, 0.0, 0.0]));
    let log = Rc::new(RefCell::new(Log::default()));

    let version = s.version;
    let mut rx_radio = radio(rx_handle, &medium, version);
    let rx_log = log.clone();
    let rx_clock = medium.clone();
    let mut power_up = sim.delay();
    sim.spawn(async move {
        embedded_hal_async::delay::DelayNs::delay_us(&mut power_up, POWER_UP_US).await;
        let mut rx = Receiver::new(Config::new(version, RfmType::Mhz433), None);
        if rx_start(&mut rx_radio, &mut rx).await.is_err() {
            return;
        }
        loop {
            let mut on_event = |event| {
                // The application gets the values now (after the telemetry reply went out).
                let now = now_us(&rx_clock);
                let mut log = rx_log.borrow_mut();
                match event {
                    RxEvent::Channels { channels_bits, .. } => {
                        log.outputs.push((now, channels_bits.to_vec()));
                    }
                    RxEvent::FailsafeStarted => log.failsafe_at_us.push(now),
                    RxEvent::Bound(_) | RxEvent::Serial(_) => {}
                }
            };
            if rx_step(&mut rx_radio, &mut rx, &mut on_event)
                .await
                .is_err()
            {
                return;
            }
        }
    });

    let mut tx_radio = radio(tx_handle, &medium, version);
    let tx_log = log.clone();
    let tx_clock = medium.clone();
    let mut power_up = sim.delay();
    sim.spawn(async move {
        embedded_hal_async::delay::DelayNs::delay_us(&mut power_up, 2 * POWER_UP_US).await;
        let until = tx_radio.now_us() + BIND_WINDOW_US;
        let bound = tx_bind(&mut tx_radio, &data, until).await.unwrap_or(false);
        tx_log.borrow_mut().tx_bound = Some(bound);
        if !bound {
            return;
        }
        tx_log.borrow_mut().bound_at_us = Some(tx_radio.now_us());
        let Ok(mut tx) = Transmitter::new(data, tx_radio.now_us()) else {
            return;
        };
        if tx_start(&mut tx_radio, &tx).await.is_err() {
            return;
        }
        let mut set = |tx: &mut Transmitter| tx.set_channels(&handset(now_us(&tx_clock), count));
        loop {
            if tx_step(&mut tx_radio, &mut tx, &mut set, &mut |_| {})
                .await
                .is_err()
            {
                return;
            }
        }
    });

    let end = Duration::from_micros(us(s.duration_s));
    if let Some((from, to)) = s.cut_s {
        sim.run_for(Duration::from_micros(us(from)).min(end));
        medium.set_packet_loss(1.0);
        sim.run_for(
            Duration::from_micros(us(to))
                .min(end)
                .saturating_sub(sim.now()),
        );
        medium.set_packet_loss(s.loss);
    }
    sim.run_for(end.saturating_sub(sim.now()));

    let log = log.borrow();
    let end_us = us(s.duration_s);
    let cut = s.cut_s.map(|(a, b)| (us(a), us(b).min(end_us)));
    let in_cut = |t: u64| cut.is_some_and(|(a, b)| (a..b).contains(&t));
    let start_us = log.bound_at_us.unwrap_or(end_us);

    // Latency: the output's channel 1 names the step the handset set it at.
    let mut errors = 0;
    let mut latencies: Vec<u64> = Vec::new();
    for (t, values) in &log.outputs {
        let ok_rest = values.len() == count && values.iter().skip(1).copied().eq(fixed(count));
        let Some(&v) = values.first().filter(|_| ok_rest) else {
            errors += 1;
            continue;
        };
        let now_step = t / STEP_US;
        let back = (now_step % WRAP + WRAP - u64::from(v) % WRAP) % WRAP;
        let set_at = (now_step - back.min(now_step)) * STEP_US;
        latencies.push(t - set_at);
    }
    latencies.sort_unstable();
    let mean = |v: &[u64]| {
        #[allow(clippy::cast_precision_loss)]
        let m = v.iter().sum::<u64>() as f64 / v.len().max(1) as f64;
        m / 1000.0
    };
    #[allow(clippy::cast_precision_loss)]
    let p99 = latencies
        .get((latencies.len() * 99 / 100).min(latencies.len().saturating_sub(1)))
        .map_or(0.0, |&v| v as f64 / 1000.0);

    // Updates/s over link time: from the first output to the end, the cut taken out.
    let first = log.outputs.first().map_or(end_us, |o| o.0);
    let cut_len = cut.map_or(0, |(a, b)| b.saturating_sub(a.max(first)));
    let link_us = end_us.saturating_sub(first).saturating_sub(cut_len);
    let counted = log.outputs.iter().filter(|o| !in_cut(o.0)).count();
    #[allow(clippy::cast_precision_loss)]
    let update_rate_hz = if link_us > 0 {
        counted as f64 / (link_us as f64 / 1e6)
    } else {
        0.0
    };

    // LQ from the air trace: frames each way after the bind, outside the cut.
    let lq = |from: RadioId, to: RadioId| {
        medium.with_trace(|frames| {
            let sent: Vec<_> = frames
                .iter()
                .filter(|f| f.radio == from)
                .filter(|f| {
                    let t = u64::try_from(f.start.as_micros()).unwrap_or(u64::MAX);
                    t >= start_us && !in_cut(t)
                })
                .collect();
            let ok = sent
                .iter()
                .filter(|f| matches!(f.outcome_at(to), Some(Outcome::Delivered { .. })))
                .count();
            #[allow(clippy::cast_precision_loss)]
            let pct = 100.0 * ok as f64 / sent.len().max(1) as f64;
            pct
        })
    };
    let failsafe_ms = cut.and_then(|(a, _)| {
        log.failsafe_at_us
            .iter()
            .find(|&&t| t >= a)
            .map(|&t| (t - a) as f64 / 1000.0)
    });
    let recovery_ms = cut.and_then(|(_, b)| {
        log.outputs
            .iter()
            .find(|o| o.0 >= b)
            .map(|o| (o.0 - b) as f64 / 1000.0)
    });
    OpenLrsReport {
        protocol: match s.version {
            BindingVersion::V38 => "openlrs38",
            BindingVersion::V39 => "openlrs39",
        },
        bit_rate_bps,
        interval_us: interval,
        channels: count,
        bound: log.tx_bound == Some(true),
        update_rate_hz,
        latency_mean_ms: mean(&latencies),
        latency_p99_ms: p99,
        uplink_lq_pct: lq(RadioId(0), RadioId(1)),
        downlink_lq_pct: lq(RadioId(1), RadioId(0)),
        failsafe_ms,
        recovery_ms,
        errors,
    }
}
