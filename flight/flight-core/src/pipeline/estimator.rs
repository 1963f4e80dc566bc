//! Which estimator flies: the estimate stage's attitude (and, with the INS, the vertical and
//! horizontal navigation) comes from the 14-state INS when the settings ask for it
//! (`ins.mode`) and it is healthy, from the complementary filter otherwise.
//!
//! - `complementary` (factory): the complementary filter alone, as before the INS flew.
//!   A receiver's fixes are not fused, but the first usable one is still the home (the
//!   `Home` message, the ground station's marker), in every mode.
//! - `ins`: the full filter — gyro and accelerometer predict at the sensor rate, baro, mag
//!   and GPS ([`GpsAiding`], latency compensated) correct. While there is no usable fix the
//!   indoor pseudo-measurement stands in for GPS velocity.
//! - `ins_indoor`: no GPS (the BrushedSparky): attitude and vertical from the INS with baro
//!   and mag, the horizontal velocity held at zero by a pseudo-measurement
//!   ([`Filter::fuse_zero_horizontal_velocity`], Tau Labs' indoor mode).
//!
//! **Any start.** The complementary filter starts from the first still sample with a
//! magnetometer reading (accelerometer tilt, tilt-compensated heading against the
//! settings' declination, `estimation::align`), or after [`ALIGN_WAIT_S`] without one from
//! the tilt alone — not from level and north — so a frame powered up facing south is right
//! from the first samples, and the INS inherits that.
//!
//! **Hand-overs are seamless.** The complementary filter runs first, [`INS_START_S`] after
//! boot the INS starts *from the complementary filter's attitude and gyro bias* (and the
//! baro altitude), so the attitude the controllers see does not move at the switch. Should
//! the INS ever diverge (its state no longer finite) the complementary filter takes over
//! from the INS's last good attitude and bias, and the INS restarts from it another
//! [`INS_START_S`] later. While the INS flies the complementary filter does not run (it is
//! re-seeded at a fallback), so the two never disagree at a hand-over. Which one flies is
//! in every [`super::LoopOutput`] (`estimator`), the console's `status` and the count of
//! fallbacks.
//!
//! Cost (m4count, `tests/m4-bench` `flight_loop` regions 34–38, one whole attitude-mode
//! `FlightLoop::step` at 1 kHz; the current figures are generated into
//! `tests/flight-sitl/README.md`): a step with the INS predicting is budgeted at 3 500
//! instructions (`cargo xtask figures --check` fails above it), 27 µs at 1.3 cycles per
//! instruction on the 168 MHz F405, **under 3 % of the CPU at 1 kHz**, so the INS predicts
//! on every sample; a full correction (GPS position and velocity, baro, magnetometer) is
//! budgeted at 8 000.
//!
//! [`Filter::fuse_zero_horizontal_velocity`]: crate::estimation::ins::Filter::fuse_zero_horizontal_velocity

use ubx::NavPvt;

use super::flight_loop::ImuSample;
use crate::estimation::complementary::{self, Complementary};
use crate::estimation::ins::aiding::AidingConfig;
use crate::estimation::ins::aiding::gps::{GpsAiding, GpsAidingConfig, GpsUpdate, Home};
use crate::estimation::ins::{Config, Ins, State};
use crate::estimation::quaternion::Quaternion;
use crate::estimation::{Error, all_finite};

/// Seconds the complementary filter runs (at boot, after a fallback) before the INS
/// starts from it: long enough for the complementary filter to have levelled from its
/// level-north start (its accelerometer time constant on the ground is 1 s).
pub const INS_START_S: f32 = 2.0;
/// How long the start waits for a magnetometer sample before aligning from the tilt alone
/// (s).
pub const ALIGN_WAIT_S: f32 = 0.5;
/// The start aligns only on a still sample: specific force within this fraction of g.
const ALIGN_ACCEL_BAND: f32 = 0.05;
/// Period of the indoor pseudo-measurement, s (10 Hz, as the GPS it stands in for).
pub const PSEUDO_PERIOD_S: f32 = 0.1;
/// Variance of the indoor pseudo-measurement, (m/s)²: a hovering multirotor's horizontal
/// velocity is within ±1 m/s (2σ) most of the time.
pub const PSEUDO_VAR_M2PS2: f32 = 0.25;
/// Its variance while armed, (m/s)² (σ 20 m/s). In flight the frame does move: a bank
/// accelerates it sideways for seconds, and a tight "not moving" then tilts the estimate
/// to explain the velocity (flight-sitl `ins.rs`, a 2 s bank of 13.5°: worst roll error
/// 10.3° at 0.25, 3.1° at 25, 1.35° at 100, 0.75° at 400 — the complementary filter's
/// 0.99°). Loose as it is, it still bounds the tilt: over a 40 s hover with a 0.5 °/s gyro
/// bias the error stays within 0.74° (complementary filter 4.2°).
pub const PSEUDO_VAR_ARMED_M2PS2: f32 = 400.0;
/// Heading-frame magnetometer variance once the reading is scaled to the unit earth field
/// (≈ 6° 1σ: an uncompensated motor field).
const MAG_VAR: f32 = 0.01;
/// Attitude uncertainty given to the INS when it starts from the complementary filter:
/// tilt 2° (1σ), yaw 10°.
const START_TILT_STD_RAD: f32 = 0.035;
const START_YAW_STD_RAD: f32 = 0.17;
/// Without a baro reading for this long the INS's vertical is not trusted (s).
const BARO_TIMEOUT_S: f32 = 0.5;
/// Without a NAV-PVT for this long the fix counts as lost (µs).
const GPS_TIMEOUT_US: u64 = 1_000_000;

/// The `ins.mode` setting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EstimatorMode {
    /// The complementary filter alone.
    Complementary,
    /// The INS with GPS (indoor pseudo-measurement while there is no fix).
    Ins,
    /// The INS without GPS: horizontal velocity held by the pseudo-measurement.
    InsIndoor,
}

impl EstimatorMode {
    /// The setting's name for it.
    pub const fn name(self) -> &'static str {
        match self {
            EstimatorMode::Complementary => "complementary",
            EstimatorMode::Ins => "ins",
            EstimatorMode::InsIndoor => "ins_indoor",
        }
    }
}

/// The estimator flying now.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Source {
    /// The complementary filter.
    Complementary,
    /// The 14-state INS.
    Ins,
}

impl Source {
    /// A short name for the console.
    pub const fn name(self) -> &'static str {
        match self {
            Source::Complementary => "complementary",
            Source::Ins => "ins",
        }
    }
}

/// The estimate stage's estimators and the choice between them.
#[derive(Debug, Clone)]
pub struct Estimator {
    mode: EstimatorMode,
    cf: Complementary,
    ins: Ins,
    ins_config: Config,
    gps: GpsAiding,
    source: Source,
    /// Time the complementary filter has flown since boot or the last fallback, s.
    cf_run_s: f32,
    since_pseudo_s: f32,
    /// A baro altitude not yet fused, m.
    pending_baro_m: Option<f32>,
    last_baro_m: Option<f32>,
    since_baro_s: f32,
    /// The estimator's clock, µs since boot (advanced by each sample's period).
    time_us: u64,
    last_gps_us: Option<u64>,
    /// The INS's latest good attitude and gyro bias: what a fallback continues from.
    last_good: (Quaternion, [f32; 3]),
    fallbacks: u16,
    /// Time waited for the start's alignment (s); `None` once aligned.
    unaligned_s: Option<f32>,
}

impl Estimator {
    /// The estimators for `mode`, starting level and facing north.
    pub fn new(mode: EstimatorMode, attitude_filter: complementary::Config) -> Self {
        let ins_config = Config {
            earth_field_ned: attitude_filter.earth_field_ned,
            mag_var: MAG_VAR,
            ..Config::default()
        };
        let cf = Complementary::new(attitude_filter);
        Self {
            mode,
            cf,
            ins: Ins::new(ins_config, AidingConfig::default()),
            ins_config,
            gps: GpsAiding::new(GpsAidingConfig::default()),
            source: Source::Complementary,
            cf_run_s: 0.0,
            since_pseudo_s: 0.0,
            pending_baro_m: None,
            last_baro_m: None,
            since_baro_s: f32::INFINITY,
            time_us: 0,
            last_gps_us: None,
            last_good: (cf.attitude(), cf.gyro_bias_radps()),
            fallbacks: 0,
            unaligned_s: Some(0.0),
        }
    }

    /// The `ins.mode` in force.
    pub fn mode(&self) -> EstimatorMode {
        self.mode
    }

    /// The estimator flying now.
    pub fn source(&self) -> Source {
        self.source
    }

    /// How many times the INS fell back to the complementary filter.
    pub fn fallbacks(&self) -> u16 {
        self.fallbacks
    }

    /// Body → NED attitude from the estimator flying now.
    pub fn attitude(&self) -> Quaternion {
        match self.source {
            Source::Complementary => self.cf.attitude(),
            Source::Ins => self.ins.state().attitude,
        }
    }

    /// The attitude filter's gyro bias, rad/s (the INS's while it flies).
    pub fn gyro_bias_radps(&self) -> [f32; 3] {
        match self.source {
            Source::Complementary => self.cf.gyro_bias_radps(),
            Source::Ins => self.last_good.1,
        }
    }

    /// Starts from `attitude` and `gyro_bias_radps` kept across a reset in the air (the
    /// complementary filter flies first, as after any boot; the INS starts from it): in the
    /// air the accelerometer does not show the attitude, and it corrects only slowly while
    /// armed. A non-finite record is ignored.
    pub fn resume(&mut self, attitude: Quaternion, gyro_bias_radps: [f32; 3]) {
        if self.cf.reset(attitude, gyro_bias_radps).is_ok() {
            self.last_good = (self.cf.attitude(), gyro_bias_radps);
        }
    }

    /// The INS estimate while the INS flies.
    pub fn ins_state(&self) -> Option<State> {
        (self.source == Source::Ins).then(|| self.ins.state())
    }

    /// Altitude (m, up, the baro's origin) and climb rate (m/s, up) from the INS while it
    /// flies with a recent baro reading.
    pub fn vertical(&self) -> Option<(f32, f32)> {
        if self.source != Source::Ins || self.since_baro_s > BARO_TIMEOUT_S {
            return None;
        }
        let s = self.ins.state();
        let [_, _, pd] = s.position_ned_m;
        let [_, _, vd] = s.velocity_ned_mps;
        Some((-pd, -vd))
    }

    /// Whether a usable GPS fix came within the last second.
    pub fn gps_fix(&self) -> bool {
        self.gps.has_fix()
            && self
                .last_gps_us
                .is_some_and(|t| self.time_us.saturating_sub(t) < GPS_TIMEOUT_US)
    }

    /// Horizontal position (NED m from home) and velocity while the INS flies on a good
    /// fix: what position hold may use.
    pub fn horizontal(&self) -> Option<([f32; 2], [f32; 2])> {
        if self.source != Source::Ins || self.mode != EstimatorMode::Ins || !self.gps_fix() {
            return None;
        }
        let s = self.ins.state();
        let [n, e, _] = s.position_ned_m;
        let [vn, ve, _] = s.velocity_ned_mps;
        Some(([n, e], [vn, ve]))
    }

    /// The GPS home (the first usable fix).
    pub fn home(&self) -> Option<Home> {
        self.gps.home()
    }

    /// A baro altitude (m, up) for the next update.
    pub fn baro(&mut self, altitude_m: f32) {
        if altitude_m.is_finite() {
            self.pending_baro_m = Some(altitude_m);
        }
    }

    /// A NAV-PVT that arrived now; fused while the full INS flies. Otherwise (any other
    /// mode, or before the INS starts) it still sets the fix state and, from the first
    /// usable fix, the home — telemetry's `Home` and the ground station's marker do not need
    /// the INS. `None`: not fused and usable.
    pub fn gps(&mut self, pvt: &NavPvt) -> Option<GpsUpdate> {
        self.last_gps_us = Some(self.time_us);
        if self.mode != EstimatorMode::Ins || self.source != Source::Ins {
            return self.gps.observe(pvt).err().map(GpsUpdate::Unusable);
        }
        match self.gps.fuse(&mut self.ins, pvt, self.time_us) {
            Ok(update) => Some(update),
            Err(Error::Diverged) => {
                self.fall_back();
                None
            }
            Err(_) => None,
        }
    }

    /// One sample: the complementary filter corrects with the accelerometer only when
    /// `cf_accel_corrects` (the loop skips it on most samples while armed), the INS takes the
    /// raw specific force.
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::InvalidTimeStep`] for an unusable sample (the
    /// estimate is unchanged); a diverged INS is not an error, the complementary filter
    /// takes over.
    pub fn update(
        &mut self,
        imu: &ImuSample,
        cf_accel_corrects: bool,
        armed: bool,
        dt_s: f32,
    ) -> Result<(), Error> {
        if self.unaligned_s.is_some() {
            self.align(imu, dt_s);
        }
        match self.source {
            Source::Complementary => {
                self.cf.update_with(
                    imu.gyro_radps,
                    imu.accel_mps2,
                    cf_accel_corrects,
                    imu.mag,
                    dt_s,
                )?;
                // The factory mode stops here: nothing else to keep.
                if self.mode != EstimatorMode::Complementary {
                    self.await_ins(dt_s);
                }
                Ok(())
            }
            Source::Ins => self.update_ins(imu, armed, dt_s),
        }
    }

    /// The start: the complementary filter takes the attitude of the first still sample
    /// with a magnetometer reading, or of one without after [`ALIGN_WAIT_S`].
    #[inline(never)]
    fn align(&mut self, imu: &ImuSample, dt_s: f32) {
        let Some(waited) = self.unaligned_s.as_mut() else {
            return;
        };
        *waited += dt_s;
        let [ax, ay, az] = imu.accel_mps2;
        let g = crate::estimation::GRAVITY_MPS2;
        let f2 = ax * ax + ay * ay + az * az;
        let (low, high) = (g * (1.0 - ALIGN_ACCEL_BAND), g * (1.0 + ALIGN_ACCEL_BAND));
        let still = (low * low..high * high).contains(&f2);
        if still
            && (imu.mag.is_some() || *waited >= ALIGN_WAIT_S)
            && self.cf.align(imu.accel_mps2, imu.mag).is_ok()
        {
            self.unaligned_s = None;
        }
    }

    /// The complementary filter flies in an INS mode: keep the clock and the baro, and
    /// start the INS when it is time.
    #[inline(never)]
    fn await_ins(&mut self, dt_s: f32) {
        self.advance_clock(dt_s);
        if let Some(a) = self.pending_baro_m.take() {
            self.last_baro_m = Some(a);
            self.since_baro_s = 0.0;
        }
        self.cf_run_s += dt_s;
        if self.cf_run_s >= INS_START_S {
            self.start_ins();
        }
    }

    fn advance_clock(&mut self, dt_s: f32) {
        // To u32 first: one VCVT on the M4F, where f32 → u64 is a library call.
        self.time_us = self.time_us.wrapping_add(u64::from((dt_s * 1e6) as u32));
        self.since_baro_s += dt_s;
    }

    // Not inlined: its frame (the INS's temporaries, ≈ 1.8 kB) and register pressure would
    // otherwise burden the factory mode's step, which never runs it.
    #[inline(never)]
    fn update_ins(&mut self, imu: &ImuSample, armed: bool, dt_s: f32) -> Result<(), Error> {
        self.advance_clock(dt_s);
        match self.ins.predict(imu.gyro_radps, imu.accel_mps2, dt_s) {
            Ok(()) => {}
            Err(Error::Diverged) => {
                self.fall_back();
                return Ok(());
            }
            Err(e) => return Err(e),
        }
        let mut diverged = false;
        if let Some(a) = self.pending_baro_m.take() {
            self.last_baro_m = Some(a);
            self.since_baro_s = 0.0;
            diverged |= self.ins.baro(a) == Err(Error::Diverged);
        }
        if let Some(m) = imu.mag {
            diverged |= self.ins.mag(m) == Err(Error::Diverged);
        }
        let gps_aids = self.mode == EstimatorMode::Ins && self.gps_fix();
        if !gps_aids {
            self.since_pseudo_s += dt_s;
            if self.since_pseudo_s >= PSEUDO_PERIOD_S {
                self.since_pseudo_s = 0.0;
                diverged |= self
                    .ins
                    .filter_mut()
                    .fuse_zero_horizontal_velocity(if armed {
                        PSEUDO_VAR_ARMED_M2PS2
                    } else {
                        PSEUDO_VAR_M2PS2
                    })
                    == Err(Error::Diverged);
            }
        }
        let s = self.ins.state();
        if diverged || !all_finite(&s.attitude) {
            self.fall_back();
            return Ok(());
        }
        if self.mode == EstimatorMode::Ins {
            self.gps.record(self.time_us, &s);
        }
        self.last_good = (s.attitude, s.gyro_bias_radps);
        Ok(())
    }

    /// The INS takes over from the complementary filter: same attitude and gyro bias,
    /// vertical from the latest baro reading, at rest.
    fn start_ins(&mut self) {
        let attitude = self.cf.attitude();
        let gyro_bias_radps = self.cf.gyro_bias_radps();
        let mut ins = Ins::new(self.ins_config, AidingConfig::default());
        let filter = ins.filter_mut();
        filter.reset_attitude(
            attitude,
            START_TILT_STD_RAD * START_TILT_STD_RAD,
            START_YAW_STD_RAD * START_YAW_STD_RAD,
        );
        let state = State {
            position_ned_m: [0.0, 0.0, -self.last_baro_m.unwrap_or(0.0)],
            velocity_ned_mps: [0.0; 3],
            attitude,
            gyro_bias_radps,
            accel_bias_z_mps2: 0.0,
        };
        if filter.set_state(&state).is_err() {
            // The complementary filter's state is finite by construction; should it not
            // be, stay on it and try again later.
            self.cf_run_s = 0.0;
            return;
        }
        self.ins = ins;
        self.last_good = (attitude, gyro_bias_radps);
        self.since_pseudo_s = 0.0;
        self.source = Source::Ins;
    }

    /// The complementary filter takes over from the INS's last good estimate.
    fn fall_back(&mut self) {
        let (attitude, bias) = self.last_good;
        // `last_good` only ever holds finite values; a refusal keeps the filter's own.
        let _ = self.cf.reset(attitude, bias);
        self.source = Source::Complementary;
        self.cf_run_s = 0.0;
        self.fallbacks = self.fallbacks.saturating_add(1);
    }
}

#[cfg(test)]
mod tests;
