//! The flight loop's side: what the IMU → loop → motors path owns — the flight loop and its
//! controllers and estimators, the IMU fault policy ([`imu`]), the magnetometer calibration
//! in force — apart from the rest of the application (`flight_app::app::FlightApp`), and
//! built with the loop for speed.
//!
//! The firmware runs it in its own, higher-priority executor, and no task's call into the
//! app (a console `status`, a link step, GPS bytes) can hold it up: the two sides trade a
//! small copy each way per sample, the app's [`LoopInputs`] before the step and the loop's
//! [`LoopReport`] after it, each under the app's lock for a few hundred cycles; the step
//! itself takes no lock. What reaches the loop from a task rides the inputs: the link's
//! sticks, the baro's altitude and climb rate, a GPS fix to fuse (fused in the loop, one per
//! step), the board's standing (battery critical, settings problem, vertical estimate lost),
//! a new magnetometer calibration; a newly designed setup is handed over whole, between
//! steps, while disarmed ([`LoopSide::install`]). What the tasks read of the loop rides the
//! report: the output, the armed state, the estimators' standing, alerts, the
//! identification, raw magnetometer readings for a calibration being collected, and while a
//! flight-log profile records, the step's [`LoopSnapshot`] for the app's log ring.
//!
//! The loop also counts what it misses ([`LoopHealth`]): samples that did not come or could
//! not be read, data-ready edges that came while a step still ran, and steps that ran past
//! the next sample ([`LoopSide::timing`]).

pub mod imu;
mod snapshot;

pub use imu::{ImuFault, ImuHealth};
pub use snapshot::LoopSnapshot;

use crate::estimation::ins::aiding::gps::{GpsUpdate, Home};
use crate::estimation::magcal::MagCalibration;
use crate::outputs::Command;
use crate::pipeline::flight_state::{FlightState, STATE_WORDS};
use crate::pipeline::{
    Controllers, EstimatorMode, FlightLoop, FlightSetup, ImuSample, LinkInput, LoopOutput, Source,
};
use crate::supervisor::{Decision, FlightMode};
use crate::sysid::ekf::Identification;
use heapless::Deque;
use ubx::NavPvt;

/// The loop refreshes the flight state at least this often, ms (and at once on a change of
/// the armed state, failsafe or mode).
pub const STATE_REFRESH_MS: u32 = 10;

/// What, changed, makes the flight state due at once: armed, in the air, failsafe, mode.
pub type StateKey = (bool, bool, bool, FlightMode);

/// What the IMU adapter does after a sample (or a missing one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuStep {
    /// Commands for motors 1–4, to apply now.
    pub motors: [Command; 4],
    /// Re-initialise the sensor (it is faulted).
    pub reprobe: bool,
}

/// What the rest of the app hands the loop for one step (the default: nothing known, the
/// link down).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoopInputs {
    /// What the link delivers.
    pub link: LinkInput,
    /// The baro's climb rate, m/s up.
    pub climb_mps: Option<f32>,
    /// A baro altitude not yet given to the INS, m.
    pub baro_m: Option<f32>,
    /// A GPS fix not yet given to the INS.
    pub gps: Option<NavPvt>,
    /// The battery is at its critical level (arming refused).
    pub battery_critical: bool,
    /// The boot-time settings problem stands (arming refused).
    pub settings_problem: bool,
    /// The baro is declared failed (the hold modes fall back).
    pub vertical_lost: bool,
    /// A USB host has the console (arming refused).
    pub usb_connected: bool,
    /// A magnetometer calibration is being collected: report the raw readings.
    pub magcal_collecting: bool,
    /// A new magnetometer calibration (the settings changed).
    pub mag_cal: Option<MagCalibration>,
    /// A designed setup waits to be installed (the app's `FlightApp::take_pending_setup`).
    pub setup_pending: bool,
    /// The flight log records loop samples: report each step's [`LoopSnapshot`].
    pub log_loop: bool,
}

/// The estimators' standing, as the console and telemetry show it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimatorStatus {
    /// The estimator flying.
    pub source: Source,
    /// The `ins.mode` in force.
    pub mode: EstimatorMode,
    /// INS fallbacks to the complementary filter.
    pub fallbacks: u16,
    /// A usable GPS fix.
    pub gps_fix: bool,
    /// The GPS home, once set.
    pub home: Option<Home>,
}

/// What the loop misses, since boot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LoopHealth {
    /// Samples the loop did not fly: data-ready edges that did not come or whose read
    /// failed, and edges that came while a step still ran.
    pub missed: u32,
    /// Steps that ended after the next sample was due.
    pub overruns: u32,
}

/// Outputs whose decision or mode change the app must hear of (alerts, arming refusals),
/// oldest first: one per step at most, a few while the app's side lags behind.
pub type LoopNews = Deque<LoopOutput, 4>;

/// What the loop hands back after a step.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopReport {
    /// The loop's latest output.
    pub out: Option<LoopOutput>,
    /// Outputs with a decision (not `Steady`) or a mode change, since the app last took a
    /// report.
    pub news: LoopNews,
    /// Motors may turn.
    pub armed: bool,
    /// The loop's climb estimate, m/s up.
    pub climb_mps: Option<f32>,
    /// The estimators.
    pub estimator: EstimatorStatus,
    /// The standing IMU fault.
    pub imu_fault: Option<ImuFault>,
    /// The IMU fault disarmed the frame this step.
    pub disarmed_for_sensor: bool,
    /// An identification finished this step.
    pub identification: Option<Identification>,
    /// The raw magnetometer reading, while a calibration is collected.
    pub mag_raw: Option<[f32; 3]>,
    /// A GPS fix was fused this step, with what came of it.
    pub gps_update: Option<Option<GpsUpdate>>,
    /// What the loop missed.
    pub health: LoopHealth,
    /// The latest step's snapshot for the flight log (while it records).
    pub log: Option<LoopSnapshot>,
    /// Steps the flight log asked a snapshot of, since the app last took a report (more
    /// than one: the earlier ones were merged away, and the log marks them lost).
    pub log_steps: u32,
    /// A new setup was installed (the loop restarted) since the app last took a report.
    pub restarted: bool,
}

/// The loop's side.
#[derive(Debug, Clone)]
pub struct LoopSide {
    flight: FlightLoop,
    imu: ImuHealth,
    mag_cal: MagCalibration,
    last_out: Option<LoopOutput>,
    health: LoopHealth,
    /// The sample period, µs (for [`LoopSide::timing`]).
    period_us: u64,
    /// The last data-ready edge the loop flew, µs.
    last_edge_us: Option<u64>,
    /// When the flight state was last handed out for the resume record, and what it said.
    resume_kept: Option<(u32, StateKey)>,
    /// A setup was installed and no report has said so yet.
    restarted: bool,
}

impl LoopInputs {
    /// The inputs for this step; the one-shot measurements (baro, GPS, a calibration) are
    /// taken, so the next step does not see them again.
    pub fn take(&mut self) -> LoopInputs {
        let inputs = *self;
        self.baro_m = None;
        self.gps = None;
        self.mag_cal = None;
        inputs
    }
}

impl LoopReport {
    /// Folds a later report into one the app has not taken yet: the state is the later's,
    /// the news accumulate (the oldest go beyond four), a finished identification, a raw
    /// magnetometer reading and a GPS fusion stay until a later one replaces them.
    pub fn merge(&mut self, later: LoopReport) {
        let mut news = core::mem::take(&mut self.news);
        for out in later.news {
            if news.is_full() {
                news.pop_front();
            }
            let _ = news.push_back(out);
        }
        let disarmed = self.disarmed_for_sensor;
        let identification = later.identification.or(self.identification);
        let mag_raw = later.mag_raw.or(self.mag_raw);
        let gps_update = later.gps_update.or(self.gps_update);
        *self = LoopReport {
            news,
            disarmed_for_sensor: disarmed || later.disarmed_for_sensor,
            identification,
            mag_raw,
            gps_update,
            log_steps: self.log_steps.saturating_add(later.log_steps),
            restarted: self.restarted || later.restarted,
            ..later
        };
    }
}

impl LoopSide {
    /// The loop of `setup` with `controllers` (`None` until solved), booting at `now_ms`.
    pub fn new(
        setup: &FlightSetup,
        controllers: Option<Controllers>,
        mag_cal: MagCalibration,
        now_ms: u32,
    ) -> Self {
        Self {
            flight: FlightLoop::new(setup.loop_config, setup.mixer, controllers),
            imu: ImuHealth::new(now_ms),
            mag_cal,
            last_out: None,
            health: LoopHealth::default(),
            period_us: period_us(setup),
            last_edge_us: None,
            resume_kept: None,
            restarted: false,
        }
    }

    /// Motors may turn.
    pub fn armed(&self) -> bool {
        self.flight.armed()
    }

    /// The flight loop (read-only: estimates for logs and tests).
    pub fn flight_loop(&self) -> &FlightLoop {
        &self.flight
    }

    /// The magnetometer calibration the loop applies.
    pub fn mag_calibration(&self) -> &MagCalibration {
        &self.mag_cal
    }

    /// What the loop missed since boot.
    pub fn health(&self) -> LoopHealth {
        self.health
    }

    /// Installs a newly designed setup and its controllers (the rest of the app hands it
    /// over while the loop is disarmed; a rate change needs the chip reconfigured, so the
    /// sensor rate stays the boot's).
    pub fn install(&mut self, setup: &FlightSetup, controllers: Controllers) {
        self.flight = FlightLoop::new(setup.loop_config, setup.mixer, Some(controllers));
        self.period_us = period_us(setup);
        self.restarted = true;
    }

    /// Continues a flight after a reset in the air (`app::resume`).
    pub fn resume(&mut self, now_ms: u32, state: &FlightState) {
        self.flight.resume(now_ms, state);
    }

    /// The board's standing and the one-shot measurements, into the loop.
    fn take_inputs(&mut self, inputs: &LoopInputs) -> Option<Option<GpsUpdate>> {
        self.flight.set_battery_critical(inputs.battery_critical);
        self.flight.set_settings_problem(inputs.settings_problem);
        self.flight.set_vertical_lost(inputs.vertical_lost);
        self.flight.set_usb_connected(inputs.usb_connected);
        if let Some(cal) = inputs.mag_cal {
            self.mag_cal = cal;
        }
        if let Some(a) = inputs.baro_m {
            self.flight.on_baro_altitude(a);
        }
        #[cfg(any(feature = "gps", test))]
        let fused = inputs.gps.map(|pvt| self.flight.on_gps(&pvt));
        #[cfg(not(any(feature = "gps", test)))]
        let fused = None;
        fused
    }

    /// A sample from the IMU at `now_ms`: one loop, unless the sample is unusable (then
    /// the ride-through policy decides).
    // Never inlined into its caller (the firmware's IMU task, the app), which are built
    // for size: the step keeps this crate's speed.
    #[inline(never)]
    pub fn step(
        &mut self,
        now_ms: u32,
        sample: &ImuSample,
        inputs: &LoopInputs,
    ) -> (ImuStep, LoopReport) {
        let gps_update = self.take_inputs(inputs);
        if self.imu.check_sample(now_ms, sample).is_some() || self.imu.fault().is_some() {
            // A bad sample, or good data again not yet for long enough to trust: the
            // ride-through decides (disarmed while the fault stands).
            return self.ride_through(now_ms, gps_update);
        }
        let mag_raw = sample
            .mag
            .filter(|_| inputs.magcal_collecting && !self.armed());
        let sample = &ImuSample {
            mag: sample.mag.map(|m| self.mag_cal.apply(m)),
            ..*sample
        };
        let armed_before = self.armed();
        let out = self
            .flight
            .step(now_ms, sample, &inputs.link, inputs.climb_mps);
        self.last_out = Some(out);
        let step = ImuStep {
            motors: out.motors,
            reprobe: false,
        };
        let mut report = self.report(true, false, gps_update);
        report.mag_raw = mag_raw;
        if inputs.log_loop {
            report.log = Some(LoopSnapshot::of(
                &self.flight,
                sample,
                &inputs.link,
                armed_before,
            ));
            report.log_steps = 1;
        }
        (step, report)
    }

    /// No usable sample: the data-ready edge did not come within the adapter's poll
    /// period (`ImuFault::Stalled`) or the read failed (`ImuFault::ReadError`).
    // Never inlined into its caller (the firmware's IMU task, the app), which are built
    // for size: the step keeps this crate's speed.
    #[inline(never)]
    pub fn missing(
        &mut self,
        now_ms: u32,
        cause: ImuFault,
        inputs: &LoopInputs,
    ) -> (ImuStep, LoopReport) {
        let gps_update = self.take_inputs(inputs);
        self.health.missed = self.health.missed.saturating_add(1);
        self.imu.problem(cause);
        self.ride_through(now_ms, gps_update)
    }

    /// Holds the last command within the ride-through bound; past it, disarms once.
    fn ride_through(
        &mut self,
        now_ms: u32,
        gps_update: Option<Option<GpsUpdate>>,
    ) -> (ImuStep, LoopReport) {
        let mut disarmed = false;
        let mut fresh = false;
        if self.imu.expire(now_ms).is_some() {
            let decision = self.flight.sensor_fault();
            if let Some(out) = self.last_out.as_mut() {
                out.motors = [Command::Stopped; 4];
                out.armed = false;
                out.failsafe = false;
                out.decision = decision;
                fresh = true;
            }
            disarmed = decision == Decision::DisarmedSensorFault;
        }
        let motors = match self.last_out {
            Some(out) if self.flight.armed() => out.motors,
            _ => [Command::Stopped; 4],
        };
        let step = ImuStep {
            motors,
            reprobe: self.imu.reprobe_due(now_ms),
        };
        (step, self.report(fresh, disarmed, gps_update))
    }

    fn report(
        &mut self,
        fresh: bool,
        disarmed_for_sensor: bool,
        gps_update: Option<Option<GpsUpdate>>,
    ) -> LoopReport {
        let estimator = self.flight.estimator();
        let mut news = LoopNews::new();
        if let Some(out) = self
            .last_out
            .filter(|o| fresh && (o.decision != Decision::Steady || o.mode_changed))
        {
            let _ = news.push_back(out);
        }
        LoopReport {
            out: self.last_out,
            news,
            armed: self.flight.armed(),
            climb_mps: self.flight.climb_estimate(),
            estimator: EstimatorStatus {
                source: estimator.source(),
                mode: estimator.mode(),
                fallbacks: estimator.fallbacks(),
                gps_fix: estimator.gps_fix(),
                home: estimator.home(),
            },
            imu_fault: self.imu.fault(),
            disarmed_for_sensor,
            identification: self.flight.take_identification(),
            mag_raw: None,
            gps_update,
            health: self.health,
            log: None,
            log_steps: 0,
            restarted: core::mem::take(&mut self.restarted),
        }
    }

    /// The adapter's timing of the step it just ran: the data-ready edge it flew at
    /// `edge_us`, the step done at `done_us` (one clock, µs). Edges that came and went
    /// between this one and the last count as missed samples (the gap in whole sample
    /// periods less one, rounded); a step that ended after the next edge was due is an
    /// overrun.
    pub fn timing(&mut self, edge_us: u64, done_us: u64) {
        let period = self.period_us.max(1);
        if let Some(last) = self.last_edge_us {
            let gap = edge_us.saturating_sub(last);
            let periods = (gap + period / 2) / period;
            let missed = u32::try_from(periods.saturating_sub(1)).unwrap_or(u32::MAX);
            self.health.missed = self.health.missed.saturating_add(missed);
        }
        self.last_edge_us = Some(edge_us);
        if done_us.saturating_sub(edge_us) > period {
            self.health.overruns = self.health.overruns.saturating_add(1);
        }
    }

    /// The flight state to keep for a resume, when due at `now_ms` (every
    /// [`STATE_REFRESH_MS`], at once on a change of armed state, failsafe or mode).
    pub fn resume_state_due(&mut self, now_ms: u32) -> Option<[u32; STATE_WORDS]> {
        let state = self.flight.resume_state(now_ms);
        let key: StateKey = (state.armed, state.in_air, state.failsafe, state.mode);
        let due = self
            .resume_kept
            .is_none_or(|(t, k)| k != key || now_ms.wrapping_sub(t) >= STATE_REFRESH_MS);
        if !due {
            return None;
        }
        self.resume_kept = Some((now_ms, key));
        Some(state.encode())
    }
}

/// The setup's sample period, µs.
fn period_us(setup: &FlightSetup) -> u64 {
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)] // ≤ 1 s, positive
    let us = (setup.loop_config.ts_s * 1e6) as u64;
    us.max(1)
}
