//! The flight application: everything the flight firmware's tasks decide, as one pure
//! struct shaped like `module_core::app::App`. The firmware (and the simulator) call the
//! `on_*` methods from their tasks with the time and the peripheral's data, and carry out
//! what they return: motor commands, a sensor re-probe, a tone frequency, a watchdog feed,
//! a settings save ([`FlightApp::take_save`]) or a gain design
//! ([`FlightApp::take_design_request`]). No heap, no panics, time injected.
//!
//! Owned here: the live and stored settings and the setup derived from them; the flight
//! loop and its controllers; the IMU fault policy (`imu`); the baro climb rate; the
//! battery monitor and the tone player; the link follower's hooks, bind handling and
//! telemetry (`link`), the same over OpenLRSng (`openlrs`), and the link task's body the
//! firmware and the simulator share (`link_task`); the console's command language
//! (`console`); the watchdog check-in policy (`watchdog`) and the stretch around settings
//! saves (`save`); the GPS port (`gps`: UBX bytes in,
//! boot configuration out); the magnetometer calibration (`magcal`: collected from the
//! console, applied to every reading).

mod console;
mod gps;
mod imu;
mod link;
pub mod link_task;
mod magcal;
mod openlrs;
mod save;
mod watchdog;

#[cfg(test)]
mod magcal_tests;
#[cfg(test)]
mod phrase_tests;
#[cfg(test)]
mod tests;

pub use gps::{
    GPS_BAUD, GPS_BOOT_BAUDS, GPS_REPORT_PERIOD_MS, HOME_REPORT_PERIOD_MS, gps_baud_messages,
    gps_message, home_message,
};
pub use imu::{
    CLEAR_SAMPLES, FROZEN_SAMPLES, ImuFault, ImuHealth, REPROBE_PERIOD_MS, STALL_RIDE_THROUGH_MS,
};
pub use link::{
    BIND_WINDOW_US, BindError, BindReport, BindRequest, FAILSAFE_US, LinkStep, REPORT_PERIOD_US,
};
pub use magcal::{MagcalSession, calibration as mag_calibration};
pub use openlrs::{
    OPENLRS_FAILSAFE_DELAY, OPENLRS_RATE_CODE_BASE, openlrs_bind_window, run_openlrs_receiver,
};
pub use save::{SAVE_WATCHDOG_MS, SaveJob};
pub use watchdog::{FEED_PERIOD_MS, Task, WATCHDOG_TIMEOUT_MS, Watchdog};

use crate::alerts::{Alert, TonePlayer};
use crate::battery::{BatteryMonitor, BatteryStatus};
use crate::logging::{Entry, Event, LoopContext, Profile, Recorder};
use crate::outputs::Command;
use crate::pipeline::{
    ClimbRate, Controllers, FlightLoop, FlightSetup, ImuSample, LinkInput, LoopOutput, SetupError,
    announce_battery, from_settings, loop_alerts,
};
use crate::report::blocker_bit;
use crate::settings::{LoadProblem, Settings};
use crate::supervisor::{ArmBlocker, Decision};
use crate::sysid::ekf::Identification;

/// What the IMU adapter does after a sample (or a missing one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuStep {
    /// Commands for motors 1–4, to apply now.
    pub motors: [Command; 4],
    /// Re-initialise the sensor (it is faulted).
    pub reprobe: bool,
}

/// The flight application.
pub struct FlightApp {
    live: Settings,
    stored: Settings,
    setup: FlightSetup,
    setup_error: Option<SetupError>,
    flight: FlightLoop,
    pending_setup: Option<(FlightSetup, Controllers)>,
    design_requested: bool,
    save_requested: bool,
    imu: ImuHealth,
    last_out: Option<LoopOutput>,
    blockers: u16,
    climb: ClimbRate,
    climb_mps: Option<f32>,
    /// The tracked baro altitude when the tracker first settled: the power-up point the
    /// handset's altitude counts from (the MS5611 reads standard-atmosphere altitude).
    baro_ground_m: Option<f32>,
    battery_monitor: BatteryMonitor,
    battery: Option<BatteryStatus>,
    player: TonePlayer,
    link_input: LinkInput,
    link: link::LinkSide,
    watchdog: Watchdog,
    identified: Option<Identification>,
    settings_problem: Option<LoadProblem>,
    gps: gps::GpsPort,
    magcal: MagcalSession,
    magcal_gesture: magcal::MagcalGesture,
    /// The magnetometer calibration in force (from the live settings).
    mag_cal: crate::estimation::magcal::MagCalibration,
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
        let controllers = Controllers::design(&setup.control).ok();
        let mag_cal = magcal::calibration(&stored);
        let log = Recorder::new(log_profile(&stored), setup.loop_rate_hz);
        Some(Self {
            log,
            link: link::LinkSide::new(setup.channels),
            live: stored.clone(),
            stored,
            flight: FlightLoop::new(setup.loop_config, setup.mixer, controllers),
            battery_monitor: BatteryMonitor::new(setup.battery),
            setup,
            setup_error,
            pending_setup: None,
            design_requested: false,
            save_requested: false,
            imu: ImuHealth::new(now_ms),
            last_out: None,
            blockers: 0,
            climb: ClimbRate::new(),
            climb_mps: None,
            baro_ground_m: None,
            battery: None,
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
            magcal_gesture: magcal::MagcalGesture::default(),
            mag_cal,
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

    /// Motors may turn.
    pub fn armed(&self) -> bool {
        self.flight.armed()
    }

    /// The loop's latest output.
    pub fn last_output(&self) -> Option<&LoopOutput> {
        self.last_out.as_ref()
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
        self.imu.fault()
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

    /// The flight loop (read-only: estimates for logs and the simulator).
    pub fn flight_loop(&self) -> &FlightLoop {
        &self.flight
    }

    /// Arming blockers as telemetry's bit set; an IMU fault shows as "sensors unhealthy",
    /// an unfixed boot-time settings problem as "settings problem", both standing (not only
    /// after a refused arm).
    pub fn arming_blockers(&self) -> u16 {
        let imu = if self.imu.fault().is_some() {
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
        self.flight.set_settings_problem(true);
    }

    /// The boot-time settings problem not yet fixed by a save.
    pub fn settings_problem(&self) -> Option<LoadProblem> {
        self.settings_problem
    }

    // ---- IMU task -------------------------------------------------------------------

    /// A sample from the IMU at `now_ms`: one loop, unless the sample is unusable (then
    /// the ride-through policy decides). A new setup is installed first while disarmed.
    pub fn on_imu_sample(&mut self, now_ms: u32, sample: &ImuSample) -> ImuStep {
        self.watchdog.check_in(Task::Imu);
        if !self.flight.armed()
            && let Some((setup, controllers)) = self.pending_setup.take()
        {
            // Same sensor rate only: a rate change needs the chip reconfigured (next boot).
            self.flight = FlightLoop::new(setup.loop_config, setup.mixer, Some(controllers));
            self.battery_monitor = BatteryMonitor::new(setup.battery);
            self.link.set_channel_map(setup.channels);
            self.log
                .reconfigure(log_profile(&self.live), setup.loop_rate_hz);
            self.log.on_event(now_ms, Event::LoopRestarted);
            self.setup = setup;
        }
        if self.imu.check_sample(now_ms, sample).is_some() {
            return self.ride_through(now_ms);
        }
        if self.imu.fault().is_some() {
            // Good data again, not yet for long enough to trust: stay disarmed.
            return self.ride_through(now_ms);
        }
        // The raw reading to a calibration being collected (never while armed: arming
        // ends it), the calibrated one to the estimator.
        if self.flight.armed() && self.magcal.collecting() {
            self.magcal.cancel();
        }
        if let Some(raw) = sample.mag {
            self.magcal.offer(now_ms, raw);
        }
        let sample = &ImuSample {
            mag: sample.mag.map(|m| self.mag_cal.apply(m)),
            ..*sample
        };
        let armed_before = self.flight.armed();
        let out = self
            .flight
            .step(now_ms, sample, &self.link_input, self.climb_mps);
        self.record(out);
        if self.log.profile() != Profile::Off {
            self.log.on_loop(
                now_ms,
                &LoopContext {
                    sample,
                    flight: &self.flight,
                    out: &out,
                    link: &self.link_input,
                    armed_before,
                    baro_altitude_m: self.baro_altitude_m(),
                    arming_blockers: self.arming_blockers(),
                    imu_fault: self.imu.fault(),
                },
            );
        }
        self.on_magcal_gesture(now_ms);
        self.identified = self.flight.take_identification();
        if let Some(id) = &self.identified {
            self.link.queue_identification(id);
            self.log.on_identified(now_ms, id);
        }
        ImuStep {
            motors: out.motors,
            reprobe: false,
        }
    }

    /// No usable sample: the data-ready edge did not come within the adapter's poll
    /// period (`ImuFault::Stalled`) or the read failed (`ImuFault::ReadError`).
    pub fn on_imu_missing(&mut self, now_ms: u32, cause: ImuFault) -> ImuStep {
        self.watchdog.check_in(Task::Imu);
        self.imu.problem(cause);
        self.ride_through(now_ms)
    }

    /// Holds the last command within the ride-through bound; past it, disarms once.
    fn ride_through(&mut self, now_ms: u32) -> ImuStep {
        if self.imu.expire(now_ms).is_some() {
            let decision = self.flight.sensor_fault();
            self.log.on_event(now_ms, Event::ImuFault);
            self.log.on_event(now_ms, Event::Decision(decision));
            if let Some(out) = self.last_out.as_mut() {
                out.motors = [Command::Stopped; 4];
                out.armed = false;
                out.failsafe = false;
                out.decision = decision;
            }
            if decision == Decision::DisarmedSensorFault {
                self.player.push(Alert::SensorFault);
            }
        }
        let motors = match self.last_out {
            Some(out) if self.flight.armed() => out.motors,
            _ => [Command::Stopped; 4],
        };
        ImuStep {
            motors,
            reprobe: self.imu.reprobe_due(now_ms),
        }
    }

    fn record(&mut self, out: LoopOutput) {
        if let Decision::ArmRefused(b) = out.decision {
            self.blockers = blocker_bit(b);
        } else if out.decision == Decision::Armed {
            self.blockers = 0;
        }
        for alert in loop_alerts(&out).into_iter().flatten() {
            self.player.push(alert);
        }
        self.last_out = Some(out);
    }

    // ---- baro, battery, alerts, watchdog --------------------------------------------

    /// A baro altitude (`None`: the reading failed) at `now_ms`.
    pub fn on_baro(&mut self, now_ms: u32, altitude_m: Option<f32>) {
        self.watchdog.check_in(Task::Baro);
        self.climb_mps = altitude_m.and_then(|a| self.climb.update(now_ms, a));
        if self.climb_mps.is_some() && self.baro_ground_m.is_none() {
            self.baro_ground_m = self.climb.altitude_m();
        }
        if let Some(a) = altitude_m {
            self.log.on_baro(now_ms, a);
            self.flight.on_baro_altitude(a);
        }
    }

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
        self.flight
            .set_battery_critical(status.level == crate::battery::BatteryLevel::Critical);
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

    /// The check-in state (for the simulator's IWDG model and diagnostics).
    pub fn watchdog(&self) -> &Watchdog {
        &self.watchdog
    }

    // ---- settings: save and gain design ---------------------------------------------

    /// A setting changed: the gains adapter re-derives the setup and re-solves the gains.
    fn settings_changed(&mut self) {
        self.design_requested = true;
        self.mag_cal = magcal::calibration(&self.live);
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
        if !self.save_requested || self.flight.armed() {
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
        self.flight.set_settings_problem(false);
    }

    /// For the gains adapter: settings to design a setup and gains for (once per change).
    pub fn take_design_request(&mut self) -> Option<Settings> {
        self.watchdog.check_in(Task::Gains);
        if !core::mem::take(&mut self.design_requested) {
            return None;
        }
        Some(self.live.clone())
    }

    /// The gains adapter designed `setup` and `controllers`: installed by the IMU path as
    /// soon as the motors are stopped.
    pub fn on_designed(&mut self, setup: FlightSetup, controllers: Controllers) {
        self.pending_setup = Some((setup, controllers));
    }
}

/// The log profile the settings choose.
fn log_profile(settings: &Settings) -> Profile {
    Profile::from_index(settings.get(crate::settings::handles::LOG_PROFILE))
}
