//! The flight application: everything the flight firmware's tasks decide, as one pure
//! struct shaped like `module_core::app::App`. The firmware (and the simulator) call the
//! `on_*` methods from their tasks with the time and the peripheral's data, and carry out
//! what they return: motor commands, a sensor re-probe, a tone frequency, a watchdog feed,
//! a settings save ([`FlightApp::take_save`]) or a gain design
//! ([`FlightApp::take_design_request`]). No heap, no panics, time injected.
//!
//! Owned here: the live and stored settings and the setup derived from them; the flight
//! loop and its controllers; the IMU fault policy (`imu`); the baro climb rate and health
//! (`baro`: a failing baro declared failed, never a reset); the
//! battery monitor and the tone player; the link follower's hooks, bind handling and
//! telemetry (`link`), the same over OpenLRSng (`openlrs`), and the link task's body the
//! firmware and the simulator share (`link_task`); the console's command language
//! (`console`); the watchdog check-in policy (`watchdog`) and the stretch around settings
//! saves (`save`); the GPS port (`gps`: UBX bytes in,
//! boot configuration out); the magnetometer calibration (`magcal`: collected from the
//! console, applied to every reading); the flight controller as the radio's CRSF device
//! 0xC8 through the link (`device`: the settings table as device-tool rows); the VTX's
//! select pins (`vtx`: at boot, and after a change while disarmed).

mod baro;
mod console;
mod device;
mod gps;
mod health;
mod link;
pub mod link_task;
mod loop_side;
mod magcal;
mod openlrs;
pub mod resume;
mod save;
mod vtx;
mod watchdog;

#[cfg(test)]
mod magcal_tests;
#[cfg(test)]
mod phrase_tests;
#[cfg(test)]
mod tests;

pub use crate::loop_side::imu::{
    CLEAR_SAMPLES, FROZEN_SAMPLES, ImuFault, ImuHealth, REPROBE_PERIOD_MS, STALL_RIDE_THROUGH_MS,
};
pub use baro::{BARO_FAILED_AFTER, BARO_HEALTHY_AFTER, BARO_RETRY_MS, BaroChange, BaroHealth};
pub use device::{DEVICE_NAME, Note as DeviceNote, tree as device_tree};
pub use gps::{
    GPS_BAUD, GPS_BOOT_BAUDS, GPS_REPORT_PERIOD_MS, HOME_REPORT_PERIOD_MS, gps_baud_messages,
    gps_message, home_message,
};
pub use health::{BootFacts, HEALTH_PERIOD_US, Leds};
pub use link::{
    BIND_WINDOW_US, BindError, BindReport, BindRequest, FAILSAFE_US, LinkStep, REPORT_PERIOD_US,
};
pub use loop_side::{EstimatorStatus, ImuStep, LoopHealth, LoopInputs, LoopReport, LoopSide};
pub use magcal::{MagcalSession, calibration as mag_calibration};
pub use openlrs::{
    OPENLRS_FAILSAFE_DELAY, OPENLRS_RATE_CODE_BASE, openlrs_bind_window, run_openlrs_receiver,
};
pub use save::{SAVE_WATCHDOG_MS, SaveJob};
pub use watchdog::{
    CHECK_IN_POLLS, FEED_GAP_MAX_MS, FEED_PERIOD_MS, IWDG, IwdgSetting, LSI_MAX_HZ, LSI_MIN_HZ,
    LSI_TYP_HZ, MARGIN, POLL_LATENCY_MAX_MS, Task, WATCHDOG_TIMEOUT_MS, Watchdog,
};

use crate::alerts::TonePlayer;
use crate::battery::{BatteryMonitor, BatteryStatus};
use crate::control::design::AxisDesign;
use crate::logging::{Entry, Profile, Recorder};
use crate::pipeline::{
    ClimbRate, Controllers, FlightSetup, LinkInput, LoopOutput, SetupError, announce_battery,
    from_settings, loop_alerts,
};
use crate::report::blocker_bit;
use crate::settings::{LoadProblem, Settings};
use crate::supervisor::{ArmBlocker, Decision};
use crate::sysid::ekf::Identification;

/// The flight application.
pub struct FlightApp {
    live: Settings,
    stored: Settings,
    setup: FlightSetup,
    setup_error: Option<SetupError>,
    /// The settings the setup in force was derived from (what a resume rebuilds it from).
    flown: Settings,
    /// The loop's side while the app runs it itself (hosts); the firmware takes it to its
    /// own executor ([`FlightApp::take_loop_side`]).
    loop_side: Option<LoopSide>,
    /// The loop's latest report: what the tasks see of it.
    view: Option<LoopReport>,
    /// The Riccati solutions of the controllers flying (what a resume rebuilds them from).
    designs: Option<[AxisDesign; 3]>,
    /// A designed setup with its controllers and the settings they came from, installed
    /// as soon as the motors are stopped.
    pending_setup: Option<(FlightSetup, Controllers, Settings)>,
    /// The settings of the design request being solved.
    design_settings: Option<Settings>,
    design_requested: bool,
    save_requested: bool,
    blockers: u16,
    climb: ClimbRate,
    climb_mps: Option<f32>,
    /// A baro altitude for the loop's INS, until the loop takes it.
    pending_baro_m: Option<f32>,
    baro: BaroHealth,
    /// The tracked baro altitude when the tracker first settled: the power-up point the
    /// handset's altitude counts from (the MS5611 reads standard-atmosphere altitude).
    baro_ground_m: Option<f32>,
    battery_monitor: BatteryMonitor,
    battery: Option<BatteryStatus>,
    /// The pack is at its critical level (arming refused).
    battery_critical: bool,
    player: TonePlayer,
    link_input: LinkInput,
    link: link::LinkSide,
    watchdog: Watchdog,
    identified: Option<Identification>,
    settings_problem: Option<LoadProblem>,
    gps: gps::GpsPort,
    magcal: MagcalSession,
    /// A new magnetometer calibration for the loop (the live settings changed).
    mag_cal_changed: Option<crate::estimation::magcal::MagCalibration>,
    /// This boot resumed a flight (with the fault that reset the board, if recorded).
    resumed: Option<Option<resume::Fault>>,
    /// The gains changed since the resume record last took them.
    gains_changed: bool,
    /// Boot facts, the USB host, the health last reported.
    board: health::BoardState,
    magcal_gesture: magcal::MagcalGesture,
    /// The flight controller as the radio's CRSF device 0xC8 (`device`).
    device: device::DeviceSide,
    /// The VTX channel the pins were last set to (`vtx`).
    vtx_applied: Option<crate::vtx::VtxChannel>,
    /// The flight log's ring (`logging`), drained by the logging task.
    log: Recorder,
}

/// The flight setup for `settings`, or the factory one (and why) if they do not fly.
fn setup_for(settings: &Settings) -> (Option<FlightSetup>, Option<SetupError>) {
    match from_settings(settings) {
        Ok(s) => (Some(s), None),
        Err(e) => (from_settings(&Settings::default()).ok(), Some(e)),
    }
}

impl FlightApp {
    /// The application booting at `now_ms` with the settings loaded from flash. Settings
    /// that do not make a flyable setup fall back to the factory setup (see
    /// [`FlightApp::setup_error`]); the gains are solved here (≈ 5.5 M instructions), before
    /// anything can arm. `None` only if not even the factory settings make a setup.
    pub fn new(stored: Settings, now_ms: u32) -> Option<Self> {
        let (setup, setup_error) = setup_for(&stored);
        let setup = setup?;
        let controllers = crate::gains::design(&setup.control).ok();
        let flown = if setup_error.is_some() {
            Settings::default()
        } else {
            stored.clone()
        };
        Self::with_setup(
            stored,
            flown,
            (setup, setup_error),
            controllers,
            now_ms,
            None,
        )
    }

    /// The application with a setup (and why it is not the stored one) and controllers
    /// already made from `flown`, resuming the flight `resumed` describes (always `Some`). Built straight into its caller's result,
    /// once, out of line: the app is ≈ 25 KiB, and every move of it is a copy on the boot's
    /// stack (the firmware writes the result to its static storage).
    #[inline(never)]
    fn with_setup(
        stored: Settings,
        flown: Settings,
        (setup, setup_error): (FlightSetup, Option<SetupError>),
        controllers: Option<Controllers>,
        now_ms: u32,
        resumed: Option<&resume::Resume>,
    ) -> Option<Self> {
        let mag_cal = magcal::calibration(&stored);
        let mut loop_side = LoopSide::new(&setup, controllers, mag_cal, now_ms);
        if let Some(r) = resumed {
            loop_side.resume(now_ms, &r.state);
        }
        Some(Self {
            log: Recorder::new(log_profile(&stored), setup.loop_rate_hz),
            link: link::LinkSide::new(setup.channels),
            live: resumed.map_or_else(|| stored.clone(), |r| r.settings.clone()),
            stored,
            flown,
            designs: controllers.map(|c| *c.designs()),
            loop_side: Some(loop_side),
            view: None,
            battery_monitor: BatteryMonitor::new(setup.battery),
            setup,
            setup_error,
            pending_setup: None,
            design_settings: None,
            design_requested: false,
            save_requested: false,
            blockers: 0,
            climb: ClimbRate::new(),
            climb_mps: None,
            pending_baro_m: None,
            baro: BaroHealth::default(),
            baro_ground_m: None,
            battery: None,
            battery_critical: false,
            player: TonePlayer::new(),
            link_input: LinkInput {
                mode_channel: -1.0,
                ..LinkInput::default()
            },
            watchdog: Watchdog::new(now_ms),
            identified: None,
            settings_problem: None,
            gps: gps::GpsPort::new(),
            magcal: MagcalSession::default(),
            mag_cal_changed: None,
            resumed: resumed.map(|r| r.fault),
            gains_changed: true,
            board: health::BoardState::default(),
            magcal_gesture: magcal::MagcalGesture::default(),
            device: device::DeviceSide::default(),
            vtx_applied: None,
        })
    }

    /// The setup in force (motor protocol, loop rate: the firmware starts its peripherals
    /// from it).
    pub fn setup(&self) -> &FlightSetup {
        &self.setup
    }

    /// Why the stored settings were not used at boot, if they were not.
    pub fn setup_error(&self) -> Option<SetupError> {
        self.setup_error
    }

    /// The live settings.
    pub fn settings(&self) -> &Settings {
        &self.live
    }

    /// Motors may turn (as the loop last reported; before its first report, as it starts).
    pub fn armed(&self) -> bool {
        match &self.view {
            Some(v) => v.armed,
            None => self.loop_side.as_ref().is_some_and(LoopSide::armed),
        }
    }

    /// The loop's latest output.
    pub fn last_output(&self) -> Option<&LoopOutput> {
        self.view.as_ref().and_then(|v| v.out.as_ref())
    }

    /// What the loop missed since boot (its latest report).
    pub fn loop_health(&self) -> LoopHealth {
        self.view.as_ref().map(|v| v.health).unwrap_or_default()
    }

    /// What the link delivers to the loop now.
    pub fn link_input(&self) -> LinkInput {
        self.link_input
    }

    /// The identification that finished on the latest sample (system-identification mode
    /// left); it also goes down the link.
    pub fn identification_finished(&self) -> Option<Identification> {
        self.identified
    }

    /// The standing IMU fault.
    pub fn imu_fault(&self) -> Option<ImuFault> {
        self.view.as_ref().and_then(|v| v.imu_fault)
    }

    /// The latest battery reading.
    pub fn battery(&self) -> Option<BatteryStatus> {
        self.battery
    }

    /// The oldest flight-log entry not yet taken (the logging task drains them and encodes
    /// them with `logging::Encoder`).
    pub fn take_log_entry(&mut self) -> Option<Entry> {
        self.log.pop()
    }

    /// The flight log's recorder (profile, entries waiting, entries dropped).
    pub fn log_recorder(&self) -> &Recorder {
        &self.log
    }

    /// Arming blockers as telemetry's bit set; an IMU fault shows as "sensors unhealthy",
    /// an unfixed boot-time settings problem as "settings problem", both standing (not only
    /// after a refused arm).
    pub fn arming_blockers(&self) -> u16 {
        let imu = if self.imu_fault().is_some() {
            blocker_bit(ArmBlocker::SensorsUnhealthy)
        } else {
            0
        };
        let settings_bit = blocker_bit(ArmBlocker::SettingsProblem);
        let settings = if self.settings_problem.is_some() {
            settings_bit
        } else {
            0
        };
        // A refusal for the settings is over once they are saved.
        (self.blockers & !settings_bit) | imu | settings
    }

    /// The storage adapter's boot-time load reported `problem` (`LoadReport::problem`):
    /// the console's `status` says it, telemetry carries it as an arming blocker, and
    /// arming is refused until the pilot saves a set (a change, or `defaults`, then
    /// `save`). The firmware calls it right after [`FlightApp::new`].
    pub fn on_settings_problem(&mut self, problem: LoadProblem) {
        self.settings_problem = Some(problem);
    }

    /// The boot-time settings problem not yet fixed by a save.
    pub fn settings_problem(&self) -> Option<LoadProblem> {
        self.settings_problem
    }

    // ---- IMU task: the loop's side is `loop_side` -------------------------------------

    fn record(&mut self, out: LoopOutput) {
        if let Decision::ArmRefused(b) = out.decision {
            self.blockers = blocker_bit(b);
        } else if matches!(out.decision, Decision::Armed | Decision::Resumed) {
            self.blockers = 0;
        }
        for alert in loop_alerts(&out).into_iter().flatten() {
            self.player.push(alert);
        }
    }

    // ---- baro, battery, alerts, watchdog --------------------------------------------

    /// Barometric altitude above the power-up point, m (the tracked baro altitude less its
    /// value when the tracker first settled); `None` before that or while the baro fails.
    pub fn baro_altitude_m(&self) -> Option<f32> {
        self.climb_mps?;
        Some(self.climb.altitude_m()? - self.baro_ground_m?)
    }

    /// A battery sample (raw ADC counts) at `now_ms`.
    pub fn on_battery(&mut self, now_ms: u32, voltage_raw: u16, current_raw: Option<u16>) {
        self.watchdog.check_in(Task::Battery);
        let status = self
            .battery_monitor
            .update(now_ms, voltage_raw, current_raw);
        if status.level_changed || self.battery.is_none() {
            announce_battery(&mut self.player, status.level);
        }
        // Arming is refused on a critical pack (unless `arm.critical_battery allow`).
        self.battery_critical = status.level == crate::battery::BatteryLevel::Critical;
        self.log.on_battery(now_ms, &status);
        self.battery = Some(status);
    }

    /// The tone to play at `now_ms`, Hz (0 = silence). Call every few ms.
    pub fn on_alert_tick(&mut self, now_ms: u32) -> u16 {
        self.watchdog.check_in(Task::Alerts);
        self.player.tick(now_ms)
    }

    /// A task that has nothing to hand the app checks in.
    pub fn check_in(&mut self, task: Task) {
        self.watchdog.check_in(task);
    }

    /// The supervisor's poll at `now_ms`: `true` = feed the hardware watchdog.
    pub fn on_watchdog_poll(&mut self, now_ms: u32) -> bool {
        self.watchdog.poll(now_ms)
    }

    /// A simulator's chip counts an LSI of `lsi_hz`: the watchdog model's timeout follows
    /// (the firmware never calls it; its IWDG counts the real LSI).
    pub fn model_watchdog_lsi_hz(&mut self, lsi_hz: u32) {
        self.watchdog.set_lsi_hz(lsi_hz);
    }

    /// The check-in state (for the simulator's IWDG model and diagnostics).
    pub fn watchdog(&self) -> &Watchdog {
        &self.watchdog
    }

    // ---- settings: save and gain design ---------------------------------------------

    /// A setting changed: the gains adapter re-derives the setup and re-solves the gains.
    fn settings_changed(&mut self) {
        self.design_requested = true;
        self.mag_cal_changed = Some(magcal::calibration(&self.live));
    }

    /// The magnetometer calibration session (console `magcal`).
    pub fn magcal(&self) -> &MagcalSession {
        &self.magcal
    }

    /// Asks for the live settings to be saved.
    fn request_save(&mut self) {
        self.save_requested = true;
    }

    /// For the storage adapter: (live, stored) to write, when a save is due and the
    /// motors are stopped (a sector erase stalls the CPU). While a boot-time settings
    /// problem stands, flash does not hold what `stored` says: write the whole set
    /// (`settings::save_whole`, see [`FlightApp::save_whole`]) even if nothing changed.
    pub fn take_save(&mut self) -> Option<(Settings, Settings)> {
        if !self.save_requested || self.armed() {
            return None;
        }
        self.save_requested = false;
        Some((self.live.clone(), self.stored.clone()))
    }

    /// The save to hand out must rewrite the whole record (`settings::save_whole`): the
    /// stored copy is damaged or not what was loaded.
    pub fn save_whole(&self) -> bool {
        self.settings_problem.is_some()
    }

    /// The storage adapter wrote `saved`: a boot-time settings problem is fixed.
    pub fn on_saved(&mut self, saved: Settings) {
        self.stored = saved;
        self.settings_problem = None;
    }

    /// For the gains adapter: settings to design a setup and gains for (once per change).
    pub fn take_design_request(&mut self) -> Option<Settings> {
        self.watchdog.check_in(Task::Gains);
        if !core::mem::take(&mut self.design_requested) {
            return None;
        }
        self.design_settings = Some(self.live.clone());
        Some(self.live.clone())
    }

    /// The gains adapter designed `setup` and `controllers`: installed by the IMU path as
    /// soon as the motors are stopped.
    pub fn on_designed(&mut self, setup: FlightSetup, controllers: Controllers) {
        let flown = self
            .design_settings
            .take()
            .unwrap_or_else(|| self.live.clone());
        self.pending_setup = Some((setup, controllers, flown));
    }
}

/// The log profile the settings choose.
fn log_profile(settings: &Settings) -> Profile {
    Profile::from_index(settings.get(crate::settings::handles::LOG_PROFILE))
}
