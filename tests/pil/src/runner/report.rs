//! A PIL run's figures: flight-sitl's report of the flight (`flight_sitl::runner::report::
//! extract` on the observed record, its JSON keys unchanged), each image's own figures, the
//! PIL-only scenarios' figures, and the criteria (flight-sitl's `acceptance::check` for its
//! scenarios, plus the PIL's).
//!
//! Per image: `image_sha256`, `instructions`, `boot_ms` (reset → every embassy task polled),
//! `max_stack_bytes` (initial MSP − lowest SP seen), `cpu_load_pct` (core active vs asleep
//! in WFI/WFE; the cycle model is m4-sim's with the SoC's flash wait states and ART), and for
//! the flight image `loop_latency_p50_us`, `loop_jitter_p99_us` (p99 − median of MPU INT →
//! first motor pulse with a new command, `crate::world::timing`) and
//! `imu_samples_missed` (samples the MPU-9250 replaced before anyone read them).

use std::fmt::Write as _;

use flight_app::outputs::Command;
use flight_sitl::runner::report::fixed;
use flight_sitl::runner::{Kind as SitlKind, Plan, Report};
use flight_sitl::{Sitl, WARMUP_S};
use telemetry::messages::{Message, SettingChange};

use super::image::Image;
use super::{Kind, Options};
use crate::board::flight::FlightBoard;
use crate::board::module::ModuleBoard;
use crate::world::World;
use crate::world::machine::{Machine, MachineStats};

/// The panic scenario: the motors must be off this soon after the fault, ms (issue 29: a
/// handler that drives every motor pin off at once).
pub const MAX_MOTORS_OFF_MS: f64 = 1.0;
/// `boot`: the image's polled tasks are the spawned ones once no task was first polled for
/// this long, ns.
pub const SETTLED_NS: u64 = 1_000_000_000;
/// The setting the `settings-save` phone changes, and to what.
pub const SAVED_SETTING: (&str, f32) = ("failsafe.descent_mps", 0.9);

/// The change `settings-save`'s phone sends.
pub fn saved_change() -> SettingChange {
    let id = flight_app::settings::PARAMS
        .iter()
        .position(|p| p.name == SAVED_SETTING.0)
        .and_then(|i| u16::try_from(i).ok())
        .unwrap_or(u16::MAX);
    SettingChange {
        id,
        value: flight_app::report::f32_value(SAVED_SETTING.1),
    }
}

/// Virtual ns of scenario time `t_s`.
pub fn virtual_ns(t_s: f64) -> u64 {
    ((t_s + WARMUP_S) * 1e9).max(0.0) as u64
}

/// This thread's CPU time, s (flight-sitl's measure).
pub fn thread_cpu_s() -> Option<f64> {
    flight_sitl::runner::thread_cpu_s()
}

/// One image's figures.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageFigures {
    /// "flight" or "module".
    pub end: &'static str,
    /// The file.
    pub path: String,
    /// Its SHA-256.
    pub sha256: String,
    /// The emulated MCU's statistics.
    pub stats: MachineStats,
    /// Flight image: MPU INT → motor pulse, median and p99 − median, µs.
    pub loop_latency_p50_us: Option<f64>,
    /// …
    pub loop_jitter_p99_us: Option<f64>,
    /// Flight image: samples never read.
    pub imu_samples_missed: Option<u64>,
}

/// The PIL-only figures.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PilFigures {
    /// Telemetry messages the phone received.
    pub telemetry_messages: usize,
    /// The first one, scenario s (the link up and the HM-10 relaying).
    pub first_telemetry_s: Option<f64>,
    /// Baro conversions the MS5611 made.
    pub baro_conversions: u64,
    /// `panic`: the fault's time and whether the SoC model could inject it.
    pub panic_at_s: Option<f64>,
    /// …
    pub panic_injected: bool,
    /// `panic`: from the fault until every motor stopped, ms.
    pub motors_off_after_ms: Option<f64>,
    /// `settings-save`: the flight side echoed the change.
    pub setting_echoed: bool,
    /// `settings-save`: the flight flash holds the change at the end (None: unreadable).
    pub setting_in_flash: Option<bool>,
    /// Halts of either MCU (lockups, emulation errors), with their scenario time.
    pub halts: Vec<String>,
    /// `--console-busy`: bytes the flight console answered the host.
    pub console_answered_bytes: usize,
    /// `Gps` telemetry messages the phone received (the flight side reads its receiver).
    pub gps_messages: usize,
}

/// One run's result.
pub struct Outcome {
    /// The scenario.
    pub kind: Kind,
    /// The board's name.
    pub board: &'static str,
    /// The quantum, µs.
    pub quantum_us: f64,
    /// The timeline.
    pub plan: Plan,
    /// The record in flight-sitl's form.
    pub sitl: Sitl,
    /// flight-sitl's figures.
    pub report: Report,
    /// Flight, module.
    pub images: [ImageFigures; 2],
    /// The PIL's own.
    pub pil: PilFigures,
    /// Criteria not met, in words.
    pub failed: Vec<String>,
    /// The run's end, virtual ns.
    pub end_ns: u64,
    /// Wall-clock time of the run, s.
    pub wall_s: f64,
    /// CPU time of the run, s.
    pub cpu_s: Option<f64>,
}

fn image_figures(end: &'static str, image: &Image, stats: MachineStats) -> ImageFigures {
    ImageFigures {
        end,
        path: image.path.display().to_string(),
        sha256: image.sha256.clone(),
        stats,
        loop_latency_p50_us: None,
        loop_jitter_p99_us: None,
        imu_samples_missed: None,
    }
}

impl Outcome {
    /// Measures a finished `world`.
    pub fn measure<F: Machine<Board = FlightBoard>, M: Machine<Board = ModuleBoard>>(
        opts: &Options,
        plan: Plan,
        world: &mut World<F, M>,
        images: [&Image; 2],
        injected: Option<(u64, bool)>,
        wall_s: f64,
        cpu_s: Option<f64>,
    ) -> Self {
        let sitl = world.finish();
        let report = flight_sitl::runner::report::extract(&sitl, &plan);
        let [fi, mi] = images;
        let mut flight = image_figures("flight", fi, world.flight.stats());
        flight.loop_latency_p50_us = world.loop_timing.quantile_us(0.5);
        flight.loop_jitter_p99_us = world.loop_timing.jitter_p99_us();
        flight.imu_samples_missed = Some(world.flight.board().mpu.samples_missed());
        let module = image_figures("module", mi, world.module.stats());
        let baro_conversions = world.flight.board().baro.conversions();
        let telemetry = world.telemetry();
        let scenario_s = |t: u64| t as f64 * 1e-9 - WARMUP_S;
        let change = saved_change();
        let mut pil = PilFigures {
            telemetry_messages: telemetry.len(),
            first_telemetry_s: telemetry.first().map(|(t, _)| scenario_s(*t)),
            baro_conversions,
            setting_echoed: telemetry
                .iter()
                .any(|(_, m)| *m == Message::SettingChange(change)),
            console_answered_bytes: world.console_answered(),
            gps_messages: telemetry
                .iter()
                .filter(|(_, m)| matches!(m, Message::Gps(_)))
                .count(),
            halts: world
                .halts()
                .iter()
                .map(|(end, t, h)| format!("{end:?} at {:.3} s: {h:?}", scenario_s(*t)))
                .collect(),
            ..PilFigures::default()
        };
        if let Some((at, ok)) = injected {
            pil.panic_at_s = Some(scenario_s(at));
            pil.panic_injected = ok;
            pil.motors_off_after_ms = sitl
                .samples
                .iter()
                .find(|s| {
                    s.t_s >= scenario_s(at) && s.motors.iter().all(|m| *m == Command::Stopped)
                })
                .map(|s| (s.t_s - scenario_s(at)) * 1e3);
        }
        if opts.kind == Kind::SettingsSave {
            pil.setting_in_flash = world
                .flight
                .read_memory(
                    super::binding::FLIGHT_FLASH_BASE + super::binding::FLIGHT_SETTINGS.start,
                    super::binding::FLIGHT_SETTINGS.len(),
                )
                .map(|bytes| stored(&bytes));
        }
        let mut outcome = Self {
            kind: opts.kind,
            board: opts.board.name(),
            quantum_us: opts.quantum_ns as f64 / 1e3,
            plan,
            sitl,
            report,
            images: [flight, module],
            pil,
            failed: Vec::new(),
            end_ns: world.now_ns(),
            wall_s,
            cpu_s,
        };
        outcome.failed = outcome.check();
        outcome
    }

    /// What this run must show; every failed criterion, in words.
    pub fn check(&self) -> Vec<String> {
        let mut bad: Vec<String> = match self.kind {
            Kind::Boot => Vec::new(),
            Kind::I2cStuck => {
                // Flown as a hover: the hover's criteria hold.
                let mut r = self.report.clone();
                r.kind = SitlKind::Hover;
                flight_sitl::runner::acceptance::check(&r)
            }
            _ => flight_sitl::runner::acceptance::check(&self.report),
        };
        let mut need = |ok: bool, what: &str| {
            if !ok {
                bad.push(what.to_owned());
            }
        };
        need(self.pil.halts.is_empty(), "no MCU halted");
        let [flight, module] = &self.images;
        match self.kind {
            Kind::Boot => {
                for (f, end) in [(flight, "flight"), (module, "module")] {
                    let settled = f
                        .stats
                        .last_first_poll_ns
                        .is_some_and(|t| t + SETTLED_NS <= self.end_ns);
                    need(
                        f.stats.tasks_polled > 0 && settled,
                        &format!(
                            "every {end} task spawned and polled (none first polled in the last second)"
                        ),
                    );
                    need(
                        f.stats.watchdog_resets == 0 && f.stats.lockups == 0,
                        &format!("no {end} watchdog reset or lockup"),
                    );
                }
                need(
                    self.pil.first_telemetry_s.is_some(),
                    "telemetry reaches the phone (link up)",
                );
            }
            Kind::I2cStuck => {
                need(
                    flight.stats.watchdog_resets == 0,
                    "no flight watchdog reset",
                );
                need(
                    self.pil.baro_conversions > 0,
                    "the baro measures again (bus recovered)",
                );
            }
            Kind::SettingsSave => {
                need(
                    self.pil.setting_echoed,
                    "the flight side took the phone's change",
                );
                need(
                    self.pil.setting_in_flash == Some(true),
                    "the change is in the flight flash",
                );
                need(
                    flight.stats.watchdog_resets == 0,
                    "no flight watchdog reset",
                );
            }
            Kind::Panic => {
                need(self.pil.panic_injected, "the fault was injected");
                need(
                    self.pil
                        .motors_off_after_ms
                        .is_some_and(|ms| ms <= MAX_MOTORS_OFF_MS),
                    "every motor off within 1 ms of the panic",
                );
            }
            Kind::Hover | Kind::LinkCut | Kind::ImuStall => {}
        }
        bad
    }

    fn image_json(f: &ImageFigures) -> String {
        let num = |v: Option<f64>, d: usize| {
            v.filter(|x| x.is_finite())
                .map_or("null".into(), |x| fixed(x, d))
        };
        let mut o = format!(
            "{{\"path\":\"{}\",\"image_sha256\":\"{}\",\"instructions\":{},\"boot_ms\":{},\"tasks_polled\":{},\"tasks_in_image\":{},\"max_stack_bytes\":{},\"cpu_load_pct\":{},\"watchdog_resets\":{},\"resets\":{},\"lockups\":{}",
            f.path.replace('\\', "/").replace('"', "'"),
            f.sha256,
            f.stats.instructions,
            num(f.stats.boot_ns.map(|n| n as f64 / 1e6), 3),
            f.stats.tasks_polled,
            f.stats.tasks_total,
            f.stats
                .max_stack_bytes()
                .map_or("null".into(), |b| b.to_string()),
            num(f.stats.cpu_load_pct(), 2),
            f.stats.watchdog_resets,
            f.stats.resets,
            f.stats.lockups,
        );
        if f.end == "flight" {
            let _ = write!(
                o,
                ",\"loop_latency_p50_us\":{},\"loop_jitter_p99_us\":{},\"imu_samples_missed\":{}",
                num(f.loop_latency_p50_us, 2),
                num(f.loop_jitter_p99_us, 2),
                f.imu_samples_missed
                    .map_or("null".into(), |m| m.to_string()),
            );
        }
        o.push('}');
        o
    }

    /// One JSON object: flight-sitl's keys (its `scenario` replaced by the PIL's name), then
    /// `board`, `quantum_us`, `images` (per image), `pil` (the PIL-only figures) and
    /// `criteria_failed`.
    pub fn to_json(&self) -> String {
        let sitl = self.report.to_json();
        let rest = sitl
            .trim_start_matches('{')
            .split_once(',')
            .map_or("", |(_, rest)| rest)
            .trim_end_matches('}');
        let p = &self.pil;
        let num = |v: Option<f64>, d: usize| {
            v.filter(|x| x.is_finite())
                .map_or("null".into(), |x| fixed(x, d))
        };
        let [flight, module] = &self.images;
        let mut o = format!("{{\"scenario\":\"{}\",{rest}", self.kind.name());
        let _ = write!(
            o,
            ",\"board\":\"{}\",\"quantum_us\":{},\"images\":{{\"flight\":{},\"module\":{}}}",
            self.board,
            fixed(self.quantum_us, 1),
            Self::image_json(flight),
            Self::image_json(module),
        );
        let _ = write!(
            o,
            ",\"pil\":{{\"telemetry_messages\":{},\"first_telemetry_s\":{},\"baro_conversions\":{},\"panic_at_s\":{},\"panic_injected\":{},\"motors_off_after_ms\":{},\"setting_echoed\":{},\"setting_in_flash\":{},\"console_answered_bytes\":{},\"gps_messages\":{},\"halts\":[{}]}}",
            p.telemetry_messages,
            num(p.first_telemetry_s, 3),
            p.baro_conversions,
            num(p.panic_at_s, 3),
            p.panic_injected,
            num(p.motors_off_after_ms, 3),
            p.setting_echoed,
            p.setting_in_flash.map_or("null".into(), |b| b.to_string()),
            p.console_answered_bytes,
            p.gps_messages,
            p.halts
                .iter()
                .map(|h| format!("\"{}\"", h.replace('"', "'")))
                .collect::<Vec<_>>()
                .join(","),
        );
        let _ = write!(
            o,
            ",\"criteria_failed\":[{}]}}",
            self.failed
                .iter()
                .map(|f| format!("\"{f}\""))
                .collect::<Vec<_>>()
                .join(",")
        );
        o
    }

    /// The human summary: flight-sitl's lines, each image's, then the criteria.
    pub fn to_text(&self) -> String {
        let mut out = format!("scenario: {} (PIL, {})\n", self.kind.name(), self.board);
        for line in self.report.to_text().lines().skip(1) {
            let _ = writeln!(out, "{line}");
        }
        for f in &self.images {
            let _ = writeln!(
                out,
                "{} image: {}",
                f.end,
                Self::image_json(f).replace('"', "")
            );
        }
        if self.failed.is_empty() {
            let _ = writeln!(out, "criteria: met");
        } else {
            let _ = writeln!(out, "criteria failed: {}", self.failed.join("; "));
        }
        out
    }
}

/// Whether flight settings sectors `bytes` hold the saved setting (read with flight-core's
/// own boot load).
fn stored(bytes: &[u8]) -> bool {
    use super::binding::{FLIGHT_SETTINGS, FlashWindow};
    use sequential_storage::cache::Cache;
    use sequential_storage::map::{MapConfig, MapStorage};
    let mut window = FlashWindow::<4, 16_384>::erased(FLIGHT_SETTINGS);
    if window.load(bytes).is_err() {
        return false;
    }
    let Ok(config) = MapConfig::try_new(FLIGHT_SETTINGS) else {
        return false;
    };
    let mut map: MapStorage<u16, _, _> = MapStorage::new(window, config, Cache::new_uncached());
    let mut settings = flight_app::settings::Settings::default();
    let _ = embassy_futures::block_on(flight_app::settings::load_at_boot(&mut map, &mut settings));
    settings
        .by_name(SAVED_SETTING.0)
        .is_some_and(|v| v == flight_app::settings::Value::F32(SAVED_SETTING.1))
}
