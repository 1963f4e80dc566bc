//! One pass of the flight loop, run right after each gyro sample, in named stages:
//! estimate → supervise → guidance (link failsafe, hold mode or sticks) → controllers →
//! mix → output commands. The failsafe's guidance lives in `failsafe`, the hold modes' and
//! the sticks' in `guidance`, the stateless parts of the controller and mix stages in
//! `stages`.

use super::attitude::Attitude;
use super::controllers::Controllers;
use super::estimator::{Estimator, EstimatorMode, Source};
use super::failsafe::{FailsafeGuidance, Situation};
use super::flight_state::FlightState;
use super::guidance::{self, Guidance};
use super::hold::{Hold, Nav};
use super::identify::Sysid;
use super::stages;
use super::sticks::StickShaping;
use crate::control::mixer::Mixer;
use crate::estimation::GRAVITY_MPS2;
use crate::estimation::complementary;
use crate::estimation::ins::aiding::gps::GpsUpdate;
use crate::estimation::math::inv_sqrt;
use crate::estimation::quaternion::{Quaternion, ned_to_body};
use crate::outputs::Command;
use crate::supervisor::{
    Decision, FlightMode, Inputs, LandingDetector, LandingInputs, ModePolicy, ModeSwitch,
    Settings as SupervisorSettings, Sticks, Supervisor,
};
use crate::sysid::ekf::Identification;

const DEG_PER_RAD: f32 = 180.0 / core::f32::consts::PI;
/// A MEMS gyro saturates at 2000 deg/s; anything beyond (or non-finite) is a sensor fault.
const GYRO_LIMIT_DPS: f32 = 2200.0;
/// Time constant pulling the accelerometer-integrated climb rate towards the measured one, s.
const CLIMB_BLEND_S: f32 = 1.0;
/// Time constant of the hover-throttle estimate (a low-pass of the flying throttle), s.
const HOVER_LEARN_S: f32 = 2.0;

/// Fixed configuration of the loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopConfig {
    /// Loop period, s (the gyro's sample period).
    pub ts_s: f32,
    /// Stick shaping.
    pub shaping: StickShaping,
    /// Motor command while armed at zero throttle (keeps props spinning), 0…0.3.
    pub idle: f32,
    /// Arming and failsafe tunables.
    pub supervisor: SupervisorSettings,
    /// Flight modes on the switch's three positions.
    pub modes: [FlightMode; 3],
    /// Attitude and horizon modes use the LQG (else the attitude PID).
    pub attitude_uses_lqg: bool,
    /// Attitude filter gains (on the ground).
    pub attitude_filter: complementary::Config,
    /// While armed the accelerometer corrects the attitude on one sample in this many (1 =
    /// every sample). In flight a multirotor's accelerometer reads thrust and drag, not
    /// gravity: in a steady bank it points "level", so the ground gains would drag the
    /// estimate (and the frame) off by degrees per second. Skipping samples divides the
    /// filter's kp and ki by this factor without touching its ground behaviour.
    pub armed_accel_divider: u16,
    /// Which estimator flies (`ins.mode`).
    pub estimator: EstimatorMode,
}

/// One IMU sample, body FRD axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuSample {
    /// Angular rate, rad/s.
    pub gyro_radps: [f32; 3],
    /// Specific force, m/s² (level at rest: [0, 0, −g]).
    pub accel_mps2: [f32; 3],
    /// Magnetometer (any unit) when a fresh one came with this sample.
    pub mag: Option<[f32; 3]>,
}

/// What the link delivers this loop.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinkInput {
    /// Fresh channels (not in failsafe).
    pub up: bool,
    /// Sticks.
    pub sticks: Sticks,
    /// The arm switch, if one is configured.
    pub arm_switch: Option<bool>,
    /// The flight-mode switch channel, −1…1.
    pub mode_channel: f32,
}

/// The loop's result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopOutput {
    /// Commands for motors 1–4.
    pub motors: [Command; 4],
    /// What the supervisor decided.
    pub decision: Decision,
    /// Active flight mode.
    pub mode: FlightMode,
    /// The mode changed this loop.
    pub mode_changed: bool,
    /// Motors may turn.
    pub armed: bool,
    /// Link failsafe descent active (or its position hold, see
    /// [`super::FAILSAFE_HOLD_MS`]).
    pub failsafe: bool,
    /// Estimated attitude: roll and pitch, deg; the yaw on demand ([`Attitude::yaw_deg`]).
    pub attitude: Attitude,
    /// The estimator that flew this loop.
    pub estimator: Source,
}

/// What the loop works out once from its configuration rather than every step: the
/// low-pass gains (a division each) and the limited idle command.
#[derive(Debug, Clone, Copy)]
struct Gains {
    /// Ts / (CLIMB_BLEND_S + Ts).
    climb_blend: f32,
    /// Ts / (HOVER_LEARN_S + Ts).
    hover: f32,
    /// The idle command, limited ([`stages::idle`]).
    idle: f32,
}

impl Gains {
    fn new(config: &LoopConfig) -> Self {
        let ts_s = config.ts_s;
        Self {
            idle: stages::idle(config.idle),
            climb_blend: ts_s / (CLIMB_BLEND_S + ts_s),
            hover: ts_s / (HOVER_LEARN_S + ts_s),
        }
    }
}

/// The loop's state.
#[derive(Debug, Clone)]
pub struct FlightLoop {
    config: LoopConfig,
    gains: Gains,
    estimator: Estimator,
    supervisor: Supervisor,
    modes: ModeSwitch,
    mode: FlightMode,
    controllers: Option<Controllers>,
    mixer: Mixer<4>,
    /// Low-passed throttle while flying normally: the failsafe descent starts from it.
    hover_throttle: f32,
    /// Samples since the accelerometer last corrected the estimate while armed.
    accel_phase: u16,
    /// Whether the accelerometer corrected the complementary filter on the latest sample
    /// (what the flight log records so a replay feeds the estimator the same inputs).
    accel_corrected: bool,
    /// Blended climb rate, m/s up.
    climb_mps: Option<f32>,
    /// The throttle has been raised since arming (cleared when disarmed).
    airborne: bool,
    /// The identification while the system-identification mode flies.
    sysid: Option<Sysid>,
    /// The last finished identification, until taken.
    identification: Option<Identification>,
    /// Touchdown detection for the automatic disarms.
    landing: LandingDetector,
    /// The battery is at its critical level (arming refused).
    battery_critical: bool,
    /// Altitude/position hold loops (hold modes, failsafe hold).
    hold: Hold,
    /// The link failsafe's guidance and its state.
    failsafe: FailsafeGuidance,
    /// The boot-time settings load had a problem not yet fixed by a save (arming refused).
    settings_problem: bool,
    /// The vertical estimate's sensor (the baro) was declared failed: the hold modes fall
    /// back to attitude mode.
    vertical_lost: bool,
    /// A USB host has the console (arming refused).
    usb_connected: bool,
}

impl FlightLoop {
    /// A loop with `controllers` (`None` until the gains are solved: arming is refused).
    pub fn new(config: LoopConfig, mixer: Mixer<4>, controllers: Option<Controllers>) -> Self {
        let modes = ModeSwitch::new(config.modes);
        Self {
            config,
            gains: Gains::new(&config),
            estimator: Estimator::new(config.estimator, config.attitude_filter),
            supervisor: Supervisor::new(config.supervisor),
            mode: modes.mode(),
            modes,
            controllers,
            mixer,
            hover_throttle: 0.5,
            accel_phase: 0,
            accel_corrected: true,
            climb_mps: None,
            airborne: false,
            sysid: None,
            identification: None,
            landing: LandingDetector::new(),
            battery_critical: false,
            hold: Hold::default(),
            failsafe: FailsafeGuidance::default(),
            settings_problem: false,
            vertical_lost: false,
            usb_connected: false,
        }
    }

    /// Whether a USB host has the console (arming is refused while it does).
    pub fn set_usb_connected(&mut self, connected: bool) {
        self.usb_connected = connected;
    }

    /// The controllers flying (`None` until the gains are solved).
    pub fn controllers(&self) -> Option<&Controllers> {
        self.controllers.as_ref()
    }

    /// What a resume after a reset needs of the loop at `now_ms` (`app::resume`).
    pub fn resume_state(&self, now_ms: u32) -> FlightState {
        FlightState {
            written_ms: now_ms,
            armed: self.supervisor.motors_enabled(),
            in_air: self.airborne && !self.landing.landed(),
            failsafe: self.supervisor.failsafe_descent_mps().is_some(),
            mode: self.mode,
            hover_throttle: self.hover_throttle,
            attitude: self.estimator.attitude(),
            gyro_bias_radps: self.estimator.gyro_bias_radps(),
        }
    }

    /// Continues a flight after a reset in the air, from `state` (`app::resume`): in the
    /// air, the attitude and gyro bias, hover throttle and mode restored, in failsafe until
    /// the link decides (`Supervisor::resume`).
    pub fn resume(&mut self, now_ms: u32, state: &FlightState) {
        self.supervisor.resume(now_ms);
        self.modes.select(state.mode);
        self.mode = self.effective_mode(state.mode);
        if state.hover_throttle.is_finite() {
            self.hover_throttle = state.hover_throttle.clamp(0.05, 0.95);
        }
        self.estimator.resume(state.attitude, state.gyro_bias_radps);
        self.airborne = true;
        self.landing.airborne();
        self.failsafe.resume(now_ms);
    }

    /// The baro was declared failed (`true`) or is healthy again: while it is failed the hold
    /// modes cannot engage and an engaged one falls back to attitude mode, the throttle
    /// back on the stick (their altitude comes from it).
    pub fn set_vertical_lost(&mut self, lost: bool) {
        self.vertical_lost = lost;
    }

    /// The mode the loop flies when the switch selects `selected`: attitude mode instead of
    /// a hold mode while the vertical estimate is lost.
    pub fn effective_mode(&self, selected: FlightMode) -> FlightMode {
        if self.vertical_lost && selected.holds() {
            FlightMode::Attitude
        } else {
            selected
        }
    }

    /// The IMU delivered nothing usable for longer than the ride-through bound: disarm with
    /// [`Decision::DisarmedSensorFault`] (`Steady` if already disarmed).
    pub fn sensor_fault(&mut self) -> Decision {
        let decision = self.supervisor.sensor_fault();
        self.finish_sysid();
        decision
    }

    /// Motors may turn.
    pub fn armed(&self) -> bool {
        self.supervisor.motors_enabled()
    }

    /// Tells the loop whether the battery is at its critical level: arming is refused then
    /// unless the supervisor settings override it. The firmware calls it with each reading.
    pub fn set_battery_critical(&mut self, critical: bool) {
        self.battery_critical = critical;
    }

    /// Tells the loop whether the settings loaded at boot had a problem still unfixed:
    /// arming is refused while they do.
    pub fn set_settings_problem(&mut self, problem: bool) {
        self.settings_problem = problem;
    }

    /// Whether the touchdown detector sees the frame on the ground.
    pub fn landed(&self) -> bool {
        self.landing.landed()
    }

    /// Installs newly designed controllers (only while disarmed, or nothing changes).
    pub fn set_controllers(&mut self, controllers: Controllers) -> bool {
        if self.supervisor.motors_enabled() {
            return false;
        }
        self.controllers = Some(controllers);
        true
    }

    /// The blended climb rate, m/s up (`None` without a baro/INS rate).
    pub fn climb_estimate(&self) -> Option<f32> {
        self.climb_mps
    }

    /// Vertical complementary filter: the accelerometer's vertical acceleration (rotated to
    /// NED with the attitude estimate, gravity removed) integrated each loop, pulled towards
    /// the baro/INS rate with a 1 s time constant. The accelerometer gives the bandwidth the
    /// failsafe's climb-rate loop needs; the slow baro rate (α-β tracked, ≈ 0.2 s lag) only
    /// removes the drift, so a 0.1 m/s² accelerometer bias leaves 0.1 m/s.
    /// `r` is the attitude's rotation matrix (`ned_to_body`).
    fn fuse_climb(
        &mut self,
        measured_mps: Option<f32>,
        accel_mps2: [f32; 3],
        r: &[[f32; 3]; 3],
    ) -> Option<f32> {
        let Some(measured) = measured_mps.filter(|m| m.is_finite()) else {
            self.climb_mps = None;
            return None;
        };
        // NED down of the body-axis specific force: the third row of Rᵀ, as
        // `body_to_ned_vector` computes it.
        let [[_, _, r13], [_, _, r23], [_, _, r33]] = *r;
        let [x, y, z] = accel_mps2;
        let f_down = r13 * x + r23 * y + r33 * z;
        let up_accel = -(f_down + GRAVITY_MPS2);
        let ts = self.config.ts_s;
        let k = self.gains.climb_blend;
        let v = self.climb_mps.unwrap_or(measured);
        let v = if up_accel.is_finite() {
            v + up_accel * ts
        } else {
            v
        };
        let v = v + k * (measured - v);
        self.climb_mps = Some(v);
        self.climb_mps
    }

    /// The identification finished when the system-identification mode was left (once).
    pub fn take_identification(&mut self) -> Option<Identification> {
        self.identification.take()
    }

    /// The identification in progress, if the mode is flying.
    pub fn identification_in_progress(&self) -> Option<Identification> {
        self.sysid.as_ref().map(|s| s.ekf.result())
    }

    /// Ends a running identification, keeping its result if it saw any samples.
    fn finish_sysid(&mut self) {
        // Checked before `take`, which would rewrite the large `Option` every loop.
        if self.sysid.is_none() {
            return;
        }
        if let Some(s) = self.sysid.take() {
            let result = s.ekf.result();
            if result.samples > 0 {
                self.identification = Some(result);
            }
        }
    }

    /// Body → NED attitude estimate.
    pub fn attitude(&self) -> Quaternion {
        self.estimator.attitude()
    }

    /// The estimators and which one flies.
    pub fn estimator(&self) -> &Estimator {
        &self.estimator
    }

    /// Whether the accelerometer corrected the complementary filter on the latest sample.
    pub fn accel_corrected(&self) -> bool {
        self.accel_corrected
    }

    /// A baro altitude (m, up) for the INS's next update.
    pub fn on_baro_altitude(&mut self, altitude_m: f32) {
        self.estimator.baro(altitude_m);
    }

    /// A NAV-PVT from the GPS, just arrived (fused while the full INS flies).
    pub fn on_gps(&mut self, pvt: &ubx::NavPvt) -> Option<GpsUpdate> {
        self.estimator.gps(pvt)
    }

    /// One loop at `now_ms`. `climb_rate_mps` (up positive) comes from the INS/baro when
    /// available and makes the failsafe descent rate-controlled; the loop blends it with the
    /// accelerometer's vertical acceleration (see [`FlightLoop::climb_estimate`]).
    ///
    /// The stages, in order: estimate → supervise → (failsafe descent | setpoint) → mix.
    pub fn step(
        &mut self,
        now_ms: u32,
        imu: &ImuSample,
        link: &LinkInput,
        climb_rate_mps: Option<f32>,
    ) -> LoopOutput {
        let estimate = self.estimate(imu);
        let previous_mode = self.mode;
        let decision = self.supervise(now_ms, link, &estimate);
        // The INS's vertical velocity when it flies on the baro; else the loop's own blend.
        // The rotation matrix once per step: the climb blend, roll and pitch and the
        // hold loops' heading all read it.
        let r = ned_to_body(self.estimator.attitude());
        let climb_rate_mps = match self.estimator.vertical() {
            Some((_, climb)) => {
                self.climb_mps = Some(climb);
                Some(climb)
            }
            None => self.fuse_climb(climb_rate_mps, imu.accel_mps2, &r),
        };
        let attitude = Attitude::from_rotation(&r);
        let failsafe = self.supervisor.failsafe_descent_mps();
        // Nothing below changes the supervisor's state: read it once.
        let armed = self.supervisor.motors_enabled();
        if self.mode != FlightMode::SystemId || failsafe.is_some() || !armed {
            self.finish_sysid();
        }
        self.failsafe
            .track(failsafe.is_some(), decision, now_ms, &self.landing);
        // The navigation estimate, only where a hold loop reads it.
        let nav = (self.mode.holds() || failsafe.is_some()).then(|| {
            let [[r11, r12, _], _, _] = r;
            let h = r11 * r11 + r12 * r12;
            let inv = if h > 1e-12 { inv_sqrt(h) } else { 0.0 };
            Nav {
                vertical: self.estimator.vertical(),
                climb_mps: climb_rate_mps,
                horizontal: self.estimator.horizontal(),
                yaw_cos_sin: [r11 * inv, r12 * inv],
            }
        });
        let (motors, thrust) = if armed && estimate.gyro_ok {
            let fly = Fly {
                decision,
                mode_changed: self.mode != previous_mode,
                gyro_dps: estimate.gyro_dps,
                attitude_deg: [attitude.roll_deg, attitude.pitch_deg],
                failsafe_descent_mps: failsafe,
                climb_rate_mps,
                nav,
                now_ms,
            };
            let sticks = stages::flown_sticks(&link.sticks, link.arm_switch.is_some());
            self.fly(&fly, &sticks)
        } else {
            self.hold.reset();
            if let Some(c) = self.controllers.as_mut() {
                self.airborne = false;
                // On the ground nothing integrates.
                c.reset(estimate.gyro_dps);
            }
            ([Command::Stopped; 4], 0.0)
        };
        self.detect_landing(
            armed,
            now_ms,
            imu,
            &estimate,
            climb_rate_mps,
            thrust,
            failsafe,
        );
        LoopOutput {
            motors,
            decision,
            mode: self.mode,
            mode_changed: self.mode != previous_mode,
            armed,
            failsafe: failsafe.is_some(),
            attitude,
            estimator: self.estimator.source(),
        }
    }

    /// Estimate stage: gyro plausibility and the attitude filter update.
    fn estimate(&mut self, imu: &ImuSample) -> Estimate {
        let gyro_dps = imu.gyro_radps.map(|g| g * DEG_PER_RAD);
        // `abs() < limit` is false for NaN and ±∞: no separate finiteness test.
        let gyro_ok = gyro_dps.iter().all(|g| g.abs() < GYRO_LIMIT_DPS);
        // Armed, the accelerometer corrects on one sample in `armed_accel_divider` (it is
        // checked on every one).
        let armed = self.supervisor.motors_enabled();
        let accel_corrects = if armed {
            self.accel_phase = self.accel_phase.wrapping_add(1);
            let due = self.accel_phase >= self.config.armed_accel_divider.max(1);
            if due {
                self.accel_phase = 0;
            }
            due
        } else {
            true
        };
        self.accel_corrected = accel_corrects;
        let filter_ok = self
            .estimator
            .update(imu, accel_corrects, armed, self.config.ts_s)
            .is_ok();
        Estimate {
            gyro_dps,
            gyro_ok,
            filter_ok,
        }
    }

    /// Supervise stage: the flight-mode switch (while the link is up) and the arming /
    /// failsafe state machine.
    fn supervise(&mut self, now_ms: u32, link: &LinkInput, estimate: &Estimate) -> Decision {
        let selected = if link.up {
            self.modes.update(link.mode_channel)
        } else {
            self.modes.mode()
        };
        self.mode = self.effective_mode(selected);
        self.supervisor.update(&Inputs {
            now_ms,
            link_up: link.up,
            sticks: link.sticks,
            arm_switch: link.arm_switch,
            sensors_healthy: estimate.gyro_ok && estimate.filter_ok,
            gains_ready: self.controllers.is_some(),
            landed: self.landing.landed(),
            landing_detectable: self.climb_mps.is_some(),
            battery_critical: self.battery_critical,
            settings_problem: self.settings_problem,
            usb_connected: self.usb_connected,
        })
    }

    /// Touchdown stage: feeds the detector while armed (the automatic disarms wait for it).
    #[allow(clippy::too_many_arguments)]
    fn detect_landing(
        &mut self,
        armed: bool,
        now_ms: u32,
        imu: &ImuSample,
        estimate: &Estimate,
        climb_mps: Option<f32>,
        thrust: f32,
        failsafe_descent_mps: Option<f32>,
    ) {
        if armed && self.failsafe.holds_altitude() {
            self.landing.hold_off();
        } else if armed {
            self.landing.update(&LandingInputs {
                now_ms,
                gyro_dps: estimate.gyro_dps,
                accel_mps2: imu.accel_mps2,
                climb_mps,
                thrust,
                hover_thrust: self.hover_throttle,
                failsafe_descent_mps,
            });
        } else {
            self.landing.reset();
        }
    }

    /// Armed with a plausible gyro: the guidance (the link failsafe's, else a hold mode's,
    /// else the pilot's sticks), then the controllers, then the mix. Returns the motor
    /// commands and the collective throttle they carry.
    #[inline(always)]
    fn fly(&mut self, fly: &Fly, sticks: &Sticks) -> ([Command; 4], f32) {
        if self.controllers.is_none() {
            return ([Command::Stopped; 4], 0.0);
        }
        let guidance = self.guidance(fly, sticks);
        let Some(c) = self.controllers.as_mut() else {
            return ([Command::Stopped; 4], 0.0);
        };
        let gyro_dps = fly.gyro_dps;
        if fly.restarts_controllers() {
            c.reset(gyro_dps);
        }
        let (attitude, shaking) = match guidance {
            Guidance::Failsafe { angles_deg, .. } => {
                let setpoint = stages::angle_setpoint(angles_deg, fly.attitude_deg);
                (c.lqg(gyro_dps, setpoint), false)
            }
            Guidance::Hold { .. } | Guidance::Sticks => {
                let (out, shaking) = stages::setpoint(
                    c,
                    &mut self.sysid,
                    &self.config,
                    self.mode,
                    sticks,
                    gyro_dps,
                    fly.attitude_deg,
                    guidance.hold_angles(),
                );
                let on_ground = !self.airborne || self.landing.landed();
                let out = stages::ground_idle(c, out, sticks, on_ground, gyro_dps);
                (out, shaking)
            }
        };
        let throttle = guidance.throttle(sticks);
        let demand = stages::Demand {
            throttle,
            attitude,
            idle: self.gains.idle,
            uses_lqg: guidance.is_failsafe() || stages::uses_lqg(self.mode, &self.config),
        };
        let sysid = if shaking { self.sysid.as_mut() } else { None };
        let motors = stages::mix(c, &self.mixer, sysid, demand);
        if matches!(guidance, Guidance::Sticks) {
            self.learn_hover(throttle);
        }
        (motors, throttle)
    }

    /// 2 s low-pass (`HOVER_LEARN_S`) of the flying throttle: what hovering takes, learnt
    /// from the pilot's throttle only (the hold loops fly around it).
    #[inline(always)]
    fn learn_hover(&mut self, throttle: f32) {
        if throttle > 0.1 {
            self.airborne = true;
            let k = self.gains.hover;
            self.hover_throttle += k * (throttle - self.hover_throttle);
        }
    }

    /// Guidance stage: the link failsafe's guidance, else the pilot's (a hold mode's loops
    /// or the sticks). The hold loops start afresh when armed, resumed, on a failsafe or a
    /// mode change.
    #[inline(always)]
    fn guidance(&mut self, fly: &Fly, sticks: &Sticks) -> Guidance {
        if fly.restarts_hold() {
            self.hold.reset();
        }
        let (ts_s, hover_throttle) = (self.config.ts_s, self.hover_throttle);
        // The navigation estimate by value: a reference into `fly` keeps all of it in
        // memory, stored every loop, rather than in registers.
        let nav = fly.nav;
        let Some(descent_mps) = fly.failsafe_descent_mps else {
            return guidance::pilot(self.mode, &mut self.hold, nav, sticks, hover_throttle, ts_s);
        };
        let situation = Situation {
            now_ms: fly.now_ms,
            entered: fly.decision == Decision::FailsafeEntered,
            descent_mps,
            climb_rate_mps: fly.climb_rate_mps,
            nav,
            hover_throttle,
            ts_s,
        };
        self.failsafe.guide(&situation, &mut self.hold)
    }
}

/// What the estimate stage found this loop.
struct Estimate {
    /// Gyro, deg/s.
    gyro_dps: [f32; 3],
    /// The gyro reads finite values within its range.
    gyro_ok: bool,
    /// The attitude filter accepted the sample.
    filter_ok: bool,
}

/// What the flying stages need from the estimate and supervise stages.
struct Fly {
    decision: Decision,
    mode_changed: bool,
    gyro_dps: [f32; 3],
    /// Roll and pitch estimate, deg.
    attitude_deg: [f32; 2],
    /// Link failsafe descent active, at this rate (m/s).
    failsafe_descent_mps: Option<f32>,
    /// Blended climb rate, m/s up.
    climb_rate_mps: Option<f32>,
    /// The navigation estimate (hold modes and failsafe only).
    nav: Option<Nav>,
    /// The loop's clock, ms.
    now_ms: u32,
}

impl Fly {
    /// Whether the hold loops start afresh: on arming, a resume, a new failsafe or a mode
    /// change.
    #[inline(always)]
    fn restarts_hold(&self) -> bool {
        matches!(
            self.decision,
            Decision::Armed | Decision::FailsafeEntered | Decision::Resumed
        ) || self.mode_changed
    }

    /// Whether the controllers start afresh: on arming, a resume, the pilot's recovered
    /// control or a mode change.
    #[inline(always)]
    fn restarts_controllers(&self) -> bool {
        matches!(
            self.decision,
            Decision::Armed | Decision::ControlRecovered | Decision::Resumed
        ) || self.mode_changed
    }
}

#[cfg(test)]
mod tests;
