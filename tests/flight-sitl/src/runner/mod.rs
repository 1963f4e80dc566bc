//! The scenario runner behind the `flight-sitl` binary: named failure scenarios
//! ([`Kind`]) flown by a scripted pilot ([`pilot`]) through the world ([`crate::run`]),
//! reduced to the figures of [`report`], drawn by [`plot`], and the acceptance set of
//! issues 12 and 13 ([`acceptance`]), and the INS hold modes of issue 16 (`altitude-hold`,
//! `position-hold`, `loiter`, `link-cut --gps`; [`hold`] measures them). Tests call
//! [`run_kind`] directly, without spawning the binary.

pub mod acceptance;
pub mod cli;
pub mod hold;
pub mod pilot;
pub mod plot;
pub mod report;

use flight_app::settings::{Settings, handles};
use quad_sim::quad::QuadParams;
use telemetry::link::RateMode;

use crate::scenario::{
    FlashInjection, ImuInjection, PilotInput, Piloting, RadioInjection, Scenario, Sight,
};
use crate::world::Sitl;
use pilot::PilotPlan;
pub use report::Report;

/// A named scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Take off, climb to the altitude and hold it.
    Hover,
    /// Climb to the altitude, then the air path is cut for good.
    LinkCut,
    /// Armed on the ground, the flight controller loses power for 1 s; the pilot re-arms and
    /// takes off.
    PowerCycle,
    /// Hovering, the handset's PPM/CRSF input stops at the module for good.
    HandsetUnplugged,
    /// Hovering, the IMU's data-ready stops for 1 s.
    ImuStall,
    /// Hovering, the IMU repeats its last sample bit for bit for 1 s.
    ImuFrozen,
    /// Hovering, the flight side's RFM22B nIRQ reads low for 2 s.
    RadioStuckIrq,
    /// Hovering, the flight side's RFM22B browns out for 2 s.
    RadioBrownout,
    /// The flight settings flash is corrupted at the first boot; the pilot tries to fly.
    SettingsCorrupt,
    /// Hovering, the pack voltage falls 50 mV/s from 4.0 V until below critical.
    LowBattery,
    /// Hovering, the mode switch goes to altitude hold (throttle centred) for a minute.
    AltitudeHold,
    /// Hovering with a GPS fix, the mode switch goes to position hold (sticks centred).
    PositionHold,
    /// Position hold in loiter: the pilot pushes pitch forward for a while and releases.
    Loiter,
    /// Hovering in attitude mode, the pilot rolls to 15° (stick 1/3) for 1 s: the stick's way
    /// to the motors and the attitude loop's response.
    AttitudeStep,
    /// Hovering, the flight firmware panics: the handler stops the motors and resets, the
    /// flight resumes from the record kept across the reset (`flight_app::app::resume`).
    Panic,
    /// Hovering, a thread-mode task hangs (the loop flies on in its interrupt executor):
    /// the watchdog is no longer fed, the IWDG resets the board, the flight resumes.
    Hang,
}

impl Kind {
    /// Every scenario, in the order of the README.
    pub const ALL: [Kind; 16] = [
        Kind::Hover,
        Kind::LinkCut,
        Kind::PowerCycle,
        Kind::HandsetUnplugged,
        Kind::ImuStall,
        Kind::ImuFrozen,
        Kind::RadioStuckIrq,
        Kind::RadioBrownout,
        Kind::SettingsCorrupt,
        Kind::LowBattery,
        Kind::AltitudeHold,
        Kind::PositionHold,
        Kind::Loiter,
        Kind::AttitudeStep,
        Kind::Panic,
        Kind::Hang,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Hover => "hover",
            Kind::LinkCut => "link-cut",
            Kind::PowerCycle => "power-cycle",
            Kind::HandsetUnplugged => "handset-unplugged",
            Kind::ImuStall => "imu-stall",
            Kind::ImuFrozen => "imu-frozen",
            Kind::RadioStuckIrq => "radio-stuck-irq",
            Kind::RadioBrownout => "radio-brownout",
            Kind::SettingsCorrupt => "settings-corrupt",
            Kind::LowBattery => "low-battery",
            Kind::AltitudeHold => "altitude-hold",
            Kind::PositionHold => "position-hold",
            Kind::Loiter => "loiter",
            Kind::AttitudeStep => "attitude-step",
            Kind::Panic => "panic",
            Kind::Hang => "hang",
        }
    }

    /// The altitude the pilot climbs to when none is given, m.
    pub fn default_altitude_m(self) -> f64 {
        match self {
            Kind::LinkCut => 30.0,
            Kind::HandsetUnplugged | Kind::AltitudeHold | Kind::PositionHold | Kind::Loiter => 10.0,
            _ => 5.0,
        }
    }

    /// How long the fault lasts (None: for good, or no fault), s.
    fn fault_length_s(self) -> Option<f64> {
        match self {
            Kind::PowerCycle | Kind::ImuStall | Kind::ImuFrozen | Kind::AttitudeStep => Some(1.0),
            Kind::RadioStuckIrq | Kind::RadioBrownout => Some(2.0),
            _ => None,
        }
    }

    /// Whether the fault is a scripted event in time (`--at` applies).
    pub fn has_fault_time(self) -> bool {
        !matches!(self, Kind::Hover | Kind::SettingsCorrupt) && !self.is_hold()
    }

    /// Whether the scenario flies one of the INS hold modes (mode switch high).
    pub fn is_hold(self) -> bool {
        matches!(self, Kind::AltitudeHold | Kind::PositionHold | Kind::Loiter)
    }

    /// Whether the scenario always has a GPS receiver (position hold and loiter need one).
    pub fn needs_gps(self) -> bool {
        matches!(self, Kind::PositionHold | Kind::Loiter)
    }

    /// The hold mode on the switch's high position (`mode.switch_high`), if any.
    fn hold_mode(self) -> Option<&'static str> {
        match self {
            Kind::AltitudeHold => Some("altitude-hold"),
            Kind::PositionHold => Some("position-hold"),
            Kind::Loiter => Some("loiter"),
            _ => None,
        }
    }
}

/// What a run is asked for (the command line, or a test).
#[derive(Debug, Clone)]
pub struct Options {
    /// The link's rate mode.
    pub rate: RateMode,
    /// Seed of the world's noise and loss.
    pub seed: u64,
    /// Flight settings (factory unless changed).
    pub settings: Settings,
    /// Module settings (None: the world's pairing — factory settings bound to the flight
    /// side at the run's rate; see [`bound_module_settings`]).
    pub module_settings: Option<module_core::settings::Settings>,
    /// The airframe.
    pub quad: QuadParams,
    /// The fault's time, s (None: 3 s after the pilot starts holding the altitude; for
    /// `link-cut`, when the climb reaches it; for `power-cycle`, 4 s).
    pub at_s: Option<f64>,
    /// The altitude the pilot climbs to, m (None: the scenario's default).
    pub altitude_m: Option<f64>,
    /// Virtual duration, s (None: long enough for the scenario to play out).
    pub duration_s: Option<f64>,
    /// A GPS receiver on the flight controller (`crate::gps::GpsConfig::default()`: 5 Hz,
    /// 100 ms latency, noise). Set by [`Options::for_kind`] with the settings it needs.
    pub gps: bool,
    /// Steady wind from the north, m/s.
    pub wind_mps: f64,
}

impl Options {
    /// Factory flight and module settings on quad-sim's 250-class quad X
    /// (`QuadParams::quad_x(10, 6.5, 0.03)`), F250, seed 7.
    pub fn factory() -> Self {
        use flight_app::control::mixer::QUAD_X;
        Self {
            rate: RateMode::F250,
            seed: 7,
            settings: Settings::default(),
            module_settings: None,
            quad: QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X),
            at_s: None,
            altitude_m: None,
            duration_s: None,
            gps: false,
            wind_mps: 0.0,
        }
    }

    /// [`Options::factory`] plus what `kind` needs, with a GPS receiver if `gps` (or the
    /// scenario needs one): the full INS (`ins.mode ins`) with a receiver, the indoor INS
    /// (`ins_indoor`, baro) for altitude hold without one, and the scenario's hold mode on
    /// the mode switch's high position.
    ///
    /// # Errors
    /// Never for the factory settings (a refused setting names itself).
    pub fn for_kind(kind: Kind, gps: bool) -> Result<Self, String> {
        let mut o = Self::factory();
        o.gps = gps || kind.needs_gps();
        let ins = if o.gps {
            Some("ins")
        } else if kind.is_hold() {
            Some("ins_indoor")
        } else {
            None
        };
        let mut set = |name: &str, value: &str| {
            o.settings
                .set_text(name, value)
                .map_err(|e| format!("{name}={value}: {e}"))
        };
        if let Some(ins) = ins {
            set("ins.mode", ins)?;
        }
        if let Some(mode) = kind.hold_mode() {
            set("mode.switch_high", mode)?;
        }
        Ok(o)
    }
}

/// The bind ID the runner's pair shares, as after a bind (the world stores the module's
/// link in the flight controller's settings; binding itself is explicit and not replayed).
pub const RUNNER_BIND_ID: u32 = 0x7A11_0001;

/// The module's factory settings bound to the flight side ([`RUNNER_BIND_ID`]) at `rate`.
pub fn bound_module_settings(rate: RateMode) -> module_core::settings::Settings {
    module_core::settings::Settings {
        bind_id: RUNNER_BIND_ID,
        rate,
        ..module_core::settings::Settings::default()
    }
}

/// The timeline a run followed (what the report measures against).
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The scenario.
    pub kind: Kind,
    /// The rate mode.
    pub rate: RateMode,
    /// The seed.
    pub seed: u64,
    /// The fault starts, s.
    pub fault_at_s: Option<f64>,
    /// The fault ends, s (None: never, or no fault).
    pub fault_end_s: Option<f64>,
    /// The pilot starts holding the altitude, s.
    pub hold_from_s: Option<f64>,
    /// Virtual duration, s.
    pub duration_s: f64,
    /// The pilot.
    pub pilot: PilotPlan,
    /// A GPS receiver flew.
    pub gps: bool,
    /// The wind from the north, m/s.
    pub wind_mps: f64,
}

/// Why a run could not be made.
#[derive(Debug, Clone, PartialEq)]
pub enum RunError {
    /// The climbing frame never reached the altitude (within the probe's time).
    AltitudeNotReached {
        /// Wanted, m.
        wanted_m: f64,
        /// Highest reached, m.
        reached_m: f64,
    },
    /// The fault would come before the pilot could have armed and taken off.
    TooEarly {
        /// Asked, s.
        at_s: f64,
    },
    /// A setting the scenario needs was refused.
    Settings(String),
}

impl core::fmt::Display for RunError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::AltitudeNotReached {
                wanted_m,
                reached_m,
            } => write!(
                f,
                "the pilot's climb never reached {wanted_m} m (highest {reached_m:.1} m)"
            ),
            Self::TooEarly { at_s } => write!(
                f,
                "--at {at_s} s is before the take-off at {} s",
                pilot::TAKEOFF_S
            ),
            Self::Settings(e) => write!(f, "the scenario's settings: {e}"),
        }
    }
}

impl std::error::Error for RunError {}

/// One run's result: the record and its figures.
pub struct Outcome {
    /// The timeline.
    pub plan: Plan,
    /// The world's record.
    pub sitl: Sitl,
    /// The figures.
    pub report: Report,
    /// Wall-clock time of the final run alone (not the probe or the glances), s.
    pub wall_s: f64,
    /// CPU time of the final run alone, s (Linux: this thread's scheduler run time; None
    /// elsewhere).
    pub cpu_s: Option<f64>,
}

/// This thread's CPU time so far, s (`/proc/thread-self/schedstat`, nanoseconds on the CPU;
/// independent of other load on the machine).
pub fn thread_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = stat.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// Seconds from power back to the pilot's new arming gesture (power-cycle): boot, the
/// 3 s bind window and link acquisition.
pub const REARM_AFTER_POWER_S: f64 = 4.5;
/// Seconds from the start of the pilot's hold to a fault.
const SETTLE_S: f64 = 3.0;
/// The `attitude-step` roll stick: 1/3 of full deflection, 15° at the factory 45° limit.
pub const STEP_ROLL_STICK: f32 = 1.0 / 3.0;
/// Pack voltage at the start of the low-battery drain, mV, and the drain, mV/s.
const DRAIN_FROM_MV: f32 = 4_000.0;
const DRAIN_MV_PER_S: f32 = 50.0;

fn idle(settings: &Settings) -> f32 {
    settings.get(handles::OUTPUT_IDLE)
}

/// The runner's pilot flying a [`Plan`], with the plan's fault scripted alongside: while
/// holding the altitude the pilot glances at the frame every [`pilot::GLANCE_S`] (from the
/// hold's start until the fault, at most [`MAX_GLANCING_S`]) and holds the throttle chosen
/// from what it saw until the next; after the last glance it flies the trim.
struct PlanPilot {
    plan: Plan,
    glance_until_s: Option<f64>,
    critical_mv: f32,
}

impl PlanPilot {
    fn new(opts: &Options, mut plan: Plan) -> Self {
        plan.pilot.glances.clear();
        let glance_until_s = plan.pilot.hold_from_s.map(|from| {
            match plan.fault_at_s {
                Some(f) if f > from => f,
                _ => from + MAX_GLANCING_S,
            }
            .min(plan.duration_s)
            .min(from + MAX_GLANCING_S)
        });
        Self {
            plan,
            glance_until_s,
            critical_mv: opts.settings.get(handles::BATTERY_CELL_CRITICAL_MV) as f32,
        }
    }
}

impl Piloting for PlanPilot {
    fn input(&mut self, t: f64, sight: &Sight) -> PilotInput {
        let pilot = &mut self.plan.pilot;
        while let (Some(g), Some(until)) = (pilot.next_glance_s(), self.glance_until_s)
            && g <= until
            && t >= g
        {
            // The frame as it is now (after the last physics step): the pilot reacts from
            // here on.
            pilot.glances.push(pilot::Glance {
                t_s: g,
                altitude_m: sight.altitude_m,
                climb_mps: sight.climb_mps,
            });
        }
        let Plan {
            kind,
            fault_at_s,
            fault_end_s,
            ..
        } = self.plan;
        let mut input = pilot.input(t);
        let on = fault_at_s.is_some_and(|a| t >= a) && fault_end_s.is_none_or(|e| t < e);
        if on {
            match kind {
                Kind::LinkCut => input.link_cut = true,
                Kind::PowerCycle => input.flight_powered = false,
                Kind::HandsetUnplugged => input.handset_connected = false,
                Kind::ImuStall => input.imu = ImuInjection::Stalled,
                Kind::ImuFrozen => input.imu = ImuInjection::Frozen,
                Kind::RadioStuckIrq => input.flight_radio = RadioInjection::IrqStuckLow,
                Kind::RadioBrownout => input.flight_radio = RadioInjection::BrownOut,
                Kind::AttitudeStep => input.roll = STEP_ROLL_STICK,
                Kind::Panic => input.flight_panic = true,
                Kind::Hang => input.flight_hang = true,
                Kind::Hover
                | Kind::SettingsCorrupt
                | Kind::LowBattery
                | Kind::AltitudeHold
                | Kind::PositionHold
                | Kind::Loiter => {}
            }
        }
        if let (Kind::LowBattery, Some(a)) = (kind, fault_at_s)
            && t >= a
        {
            input.battery_mv =
                (DRAIN_FROM_MV - DRAIN_MV_PER_S * (t - a) as f32).max(self.critical_mv - 300.0);
        }
        input
    }
}

/// The world's scenario for `opts`, flown by the plan's pilot with the plan's fault (the
/// processor-in-the-loop runner flies the same).
pub fn scenario(opts: &Options, plan: Plan) -> Scenario {
    let (kind, duration_s) = (plan.kind, plan.duration_s);
    let mut s = Scenario::flown_by(
        opts.settings.clone(),
        opts.quad.clone(),
        duration_s,
        PlanPilot::new(opts, plan),
    );
    s.seed = opts.seed;
    s.rate = opts.rate;
    s.gps = opts.gps.then(crate::gps::GpsConfig::default);
    s.quad.wind_ned_mps = [opts.wind_mps, 0.0, 0.0];
    s.module_settings = opts.module_settings;
    if kind == Kind::SettingsCorrupt {
        s.flight_flash = FlashInjection::Corrupted(opts.seed);
    }
    s
}

/// When the climbing pilot's frame first reaches each of `altitudes_m`, and its climb rate
/// then: one probe run of the same world (deterministic: the real run is identical up to
/// that moment).
///
/// # Errors
/// If an altitude is not reached within the probe.
pub fn reach_times(opts: &Options, altitudes_m: &[f64]) -> Result<Vec<(f64, f64)>, RunError> {
    let top = altitudes_m.iter().copied().fold(0.0, f64::max);
    // The cruise climb settles at ≈ 2 m/s on the 250-class quad with factory gains; the
    // probe allows half that.
    let duration_s = pilot::BOOST_END_S + 5.0 + top;
    let mut plan = PilotPlan::climb(&opts.quad, idle(&opts.settings));
    plan.arm_switch = opts.settings.get(handles::ARM_CHANNEL) != 0;
    let probe = Plan {
        kind: Kind::Hover,
        rate: opts.rate,
        seed: opts.seed,
        fault_at_s: None,
        fault_end_s: None,
        hold_from_s: None,
        duration_s,
        pilot: plan,
        gps: opts.gps,
        wind_mps: opts.wind_mps,
    };
    let sitl = crate::run(scenario(opts, probe));
    let reached_m = sitl
        .samples
        .iter()
        .map(|s| s.altitude_m)
        .fold(0.0, f64::max);
    altitudes_m
        .iter()
        .map(|&wanted_m| {
            sitl.samples
                .iter()
                .find(|s| s.altitude_m >= wanted_m)
                .map(|s| (s.t_s, s.climb_mps))
                .ok_or(RunError::AltitudeNotReached {
                    wanted_m,
                    reached_m,
                })
        })
        .collect()
}

/// The timeline of `kind` under `opts`, given when the climb reaches the altitude
/// (`reach`: time, climb rate; from [`reach_times`]).
pub fn plan(kind: Kind, opts: &Options, reach: (f64, f64)) -> Result<Plan, RunError> {
    let mut pilot = PilotPlan::climb(&opts.quad, idle(&opts.settings));
    pilot.arm_switch = opts.settings.get(handles::ARM_CHANNEL) != 0;
    let (t_reach, _) = reach;
    let descent = f64::from(opts.settings.get(handles::FAILSAFE_DESCENT_MPS)).max(0.1);
    let altitude = opts.altitude_m.unwrap_or(kind.default_altitude_m());
    let (fault_at_s, hold_from_s, duration_s) = match kind {
        Kind::LinkCut => {
            let at = opts.at_s.unwrap_or(t_reach);
            // Climb on to the cut; failsafe after 0.5 s; the descent from the peak (the
            // climb coasts ≈ 1 m on), touchdown and its detection.
            let top = altitude.max(2.5 * (at - pilot::TAKEOFF_S)) + 5.0;
            // With a fix the failsafe first holds the position and altitude.
            let held = if opts.gps {
                f64::from(flight_app::pipeline::FAILSAFE_HOLD_MS) / 1_000.0
            } else {
                0.0
            };
            (Some(at), None, at + held + top / descent + 12.0)
        }
        Kind::PowerCycle => {
            pilot.take_off = false;
            let at = opts.at_s.unwrap_or(4.0);
            (Some(at), None, at + 1.0 + REARM_AFTER_POWER_S + 10.0)
        }
        Kind::HandsetUnplugged => {
            let at = opts.at_s.unwrap_or(t_reach + SETTLE_S);
            (
                Some(at),
                Some(t_reach),
                at + (altitude + 5.0) / descent + 12.0,
            )
        }
        Kind::SettingsCorrupt => (None, Some(t_reach), t_reach + SETTLE_S),
        Kind::Hover => (None, Some(t_reach), t_reach + 10.0),
        Kind::LowBattery => {
            let at = opts.at_s.unwrap_or(t_reach + SETTLE_S);
            let critical = opts.settings.get(handles::BATTERY_CELL_CRITICAL_MV) as f64;
            let drain = (f64::from(DRAIN_FROM_MV) - critical) / f64::from(DRAIN_MV_PER_S);
            (Some(at), Some(t_reach), at + drain + 3.0)
        }
        Kind::AttitudeStep => {
            let at = opts.at_s.unwrap_or(t_reach + SETTLE_S);
            (Some(at), Some(t_reach), at + 3.0)
        }
        Kind::ImuStall
        | Kind::ImuFrozen
        | Kind::RadioStuckIrq
        | Kind::RadioBrownout
        | Kind::Panic
        | Kind::Hang => {
            let at = opts.at_s.unwrap_or(t_reach + SETTLE_S);
            (Some(at), Some(t_reach), at + 8.0)
        }
        Kind::AltitudeHold | Kind::PositionHold | Kind::Loiter => {
            let timeline = hold::Timeline::of(kind, t_reach);
            pilot.engage_s = Some(timeline.engage_s);
            pilot.push = timeline.push;
            (None, Some(t_reach), timeline.end_s)
        }
    };
    if let Some(at) = fault_at_s
        && at < pilot::TAKEOFF_S
        && kind != Kind::PowerCycle
    {
        return Err(RunError::TooEarly { at_s: at });
    }
    if let Some(h) = hold_from_s {
        pilot = pilot.hold(h, altitude);
    }
    let fault_end_s = fault_at_s.zip(kind.fault_length_s()).map(|(a, l)| a + l);
    if kind == Kind::PowerCycle {
        // Back on the ground after the reboot: the pilot re-arms once the link is back
        // (the flight side boots in ≈ 0.15 s, listens for a bind for 3 s, then acquires).
        pilot.rearm_s = fault_end_s.map(|e| e + REARM_AFTER_POWER_S);
        if let Some(r) = pilot.rearm_s {
            // Hold the altitude from the end of the take-off boost.
            pilot = pilot.hold(r + pilot::BOOST_END_S, altitude);
        }
    }
    Ok(Plan {
        kind,
        rate: opts.rate,
        seed: opts.seed,
        fault_at_s,
        fault_end_s,
        hold_from_s,
        duration_s: opts.duration_s.unwrap_or(duration_s),
        pilot,
        gps: opts.gps,
        wind_mps: opts.wind_mps,
    })
}

/// Runs `kind` under `opts`: the probe for the altitude, then the scenario, then its figures.
///
/// # Errors
/// If the altitude is not reached or the fault time is impossible.
pub fn run_kind(kind: Kind, opts: &Options) -> Result<Outcome, RunError> {
    let altitude = opts.altitude_m.unwrap_or(kind.default_altitude_m());
    let reach = if kind == Kind::PowerCycle {
        (0.0, 0.0)
    } else {
        // A pilot who holds starts easing off before the altitude (the climb takes ≈ 2 m to
        // spend); link-cut cuts at the altitude itself.
        let start = if kind == Kind::LinkCut {
            altitude
        } else {
            (altitude - pilot::HOLD_LEAD_M).max(altitude / 2.0)
        };
        reach_times(opts, &[start])?
            .first()
            .copied()
            .unwrap_or((0.0, 0.0))
    };
    Ok(run_plan(opts, plan(kind, opts, reach)?))
}

/// Writes the flight controller's logs of a run: the first boot's to `path`, each later
/// boot's next to it as `STEM.bootN.ulg`.
///
/// # Errors
/// A file that cannot be written.
pub fn write_logs(path: &std::path::Path, logs: &[Vec<u8>]) -> std::io::Result<()> {
    for (i, bytes) in logs.iter().enumerate() {
        let file = if i == 0 {
            path.to_path_buf()
        } else {
            path.with_extension(format!("boot{}.ulg", i + 1))
        };
        std::fs::write(file, bytes)?;
    }
    Ok(())
}

/// The pilot's glances at most this long after the hold starts, s.
pub const MAX_GLANCING_S: f64 = 8.0;

/// Runs a planned scenario and measures it.
pub fn run_plan(opts: &Options, plan: Plan) -> Outcome {
    let started = std::time::Instant::now();
    let cpu_before = thread_cpu_s();
    let sitl = crate::run(scenario(opts, plan.clone()));
    let wall_s = started.elapsed().as_secs_f64();
    let cpu_s = thread_cpu_s().zip(cpu_before).map(|(a, b)| a - b);
    let report = report::extract(&sitl, &plan);
    Outcome {
        plan,
        sitl,
        report,
        wall_s,
        cpu_s,
    }
}
