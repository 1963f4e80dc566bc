//! A scenario = trajectory + sensor models + schedule; [`Simulation`] steps it and
//! [`Simulation::drive`] feeds an [`Ins`] the way the firmware would (predict on every IMU
//! sample, then the measurements that arrived with it).

use flight_app::estimation::ins::{Aided, Ins};

use crate::sensors::{BaroModel, Bias, GpsModel, ImuModel, MagModel, Readings};
use crate::trajectory::{Motion, Trajectory, Truth};
use sim_rng::{GOLDEN_GAMMA, SplitMix64};

/// Everything that defines a simulated run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scenario {
    /// What the craft does.
    pub motion: Motion,
    /// Initial position NED (m).
    pub position_ned_m: [f64; 3],
    /// Initial velocity NED (m/s).
    pub velocity_ned_mps: [f64; 3],
    /// Initial attitude.
    pub attitude: [f64; 4],
    /// IMU model.
    pub imu: ImuModel,
    /// Magnetometer model.
    pub mag: MagModel,
    /// Barometer model.
    pub baro: BaroModel,
    /// GPS model.
    pub gps: GpsModel,
    /// Whether GPS height is fused (the reference uses baro only for the vertical).
    pub gps_vertical: bool,
    /// Noise seed.
    pub seed: u64,
}

impl Scenario {
    /// The Tau Labs test set-up (flight-core's `DERIVATION.md` §7) at realistic rates: IMU 500 Hz,
    /// mag and baro 50 Hz, GPS 10 Hz; noise 1e-3 on gyro, accel, GPS and baro, 10 on the
    /// magnetometer (Be = [400, 0, 1600]); static, level, at the origin, facing north.
    #[must_use]
    pub fn reference(noise: bool) -> Self {
        let n = if noise { 1e-3 } else { 0.0 };
        Self {
            motion: Motion::Static,
            position_ned_m: [0.0; 3],
            velocity_ned_mps: [0.0; 3],
            attitude: [1.0, 0.0, 0.0, 0.0],
            imu: ImuModel {
                rate_hz: 500.0,
                gyro_bias: Bias::default(),
                accel_bias: Bias::default(),
                gyro_scale: 1.0,
                accel_scale: 1.0,
                gyro_noise: n,
                accel_noise: n,
            },
            mag: MagModel {
                rate_hz: 50.0,
                earth_field_ned: [400.0, 0.0, 1600.0],
                fixed_body: None,
                scale: [1.0; 3],
                noise: if noise { 10.0 } else { 0.0 },
            },
            baro: BaroModel {
                rate_hz: 50.0,
                offset_m: 0.0,
                noise_m: n,
            },
            gps: GpsModel {
                rate_hz: 10.0,
                position_noise_m: n,
                velocity_noise_mps: n,
            },
            gps_vertical: false,
            seed: 1,
        }
    }
}

/// One step of a simulation: the truth at the sample instant and the readings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Truth at the time of the readings.
    pub truth: Truth,
    /// Sensor readings.
    pub readings: Readings,
}

/// Outcomes of the measurements fused in one step (for tests that look at gating).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepOutcomes {
    /// Magnetometer.
    pub mag: Option<Aided>,
    /// Barometer.
    pub baro: Option<Aided>,
    /// GPS position.
    pub gps_position: Option<Aided>,
    /// GPS velocity.
    pub gps_velocity: Option<Aided>,
}

/// A running scenario.
#[derive(Debug, Clone)]
pub struct Simulation {
    scenario: Scenario,
    trajectory: Trajectory,
    rng: SplitMix64,
    step: u64,
}

/// Whether a sensor at `rate_hz` is due at IMU step `k` (with a per-sensor phase so the
/// sensors do not all arrive together, as in the reference's schedule).
fn due(k: u64, imu_rate_hz: f64, rate_hz: f64, phase: f64) -> bool {
    if rate_hz <= 0.0 {
        return false;
    }
    let period = (imu_rate_hz / rate_hz).round().max(1.0) as u64;
    k % period == ((phase * period as f64) as u64).min(period - 1)
}

impl Simulation {
    /// Starts `scenario`.
    #[must_use]
    pub fn new(scenario: Scenario) -> Self {
        let trajectory = Trajectory::new(
            scenario.motion,
            scenario.position_ned_m,
            scenario.velocity_ned_mps,
            scenario.attitude,
        );
        Self {
            scenario,
            trajectory,
            rng: SplitMix64::new(scenario.seed ^ GOLDEN_GAMMA),
            step: 0,
        }
    }

    /// IMU sample period (s).
    #[must_use]
    pub fn dt_s(&self) -> f64 {
        1.0 / self.scenario.imu.rate_hz
    }

    /// Number of IMU steps in `seconds`.
    #[must_use]
    pub fn steps_in(&self, seconds: f64) -> u64 {
        (seconds * self.scenario.imu.rate_hz).round() as u64
    }

    /// Advances by one IMU period and returns the sample at the new instant.
    pub fn next_sample(&mut self) -> Sample {
        self.trajectory.advance(self.dt_s());
        self.step += 1;
        let s = &self.scenario;
        let truth = *self.trajectory.truth();
        let (gyro_radps, accel_mps2) = s.imu.read(&truth, &mut self.rng);
        let k = self.step;
        let rate = s.imu.rate_hz;
        let mag = due(k, rate, s.mag.rate_hz, 0.3).then(|| s.mag.read(&truth, &mut self.rng));
        let baro_m = due(k, rate, s.baro.rate_hz, 0.7).then(|| s.baro.read(&truth, &mut self.rng));
        let gps = due(k, rate, s.gps.rate_hz, 0.99).then(|| s.gps.read(&truth, &mut self.rng));
        Sample {
            truth,
            readings: Readings {
                gyro_radps,
                accel_mps2,
                mag,
                baro_m,
                gps,
            },
        }
    }

    /// Feeds one sample to `ins`: predict, then GPS, baro and mag if present.
    ///
    /// # Panics
    /// If the INS refuses an input (the simulator only produces finite values).
    pub fn drive(&self, ins: &mut Ins, sample: &Sample) -> StepOutcomes {
        let r = &sample.readings;
        #[allow(clippy::expect_used)] // simulator harness: a refusal is a test failure
        {
            ins.predict(r.gyro_radps, r.accel_mps2, self.dt_s() as f32)
                .expect("predict");
            let mut out = StepOutcomes::default();
            if let Some((pos, vel)) = r.gps {
                out.gps_position = Some(
                    ins.gps_position(pos, self.scenario.gps_vertical)
                        .expect("gps position"),
                );
                out.gps_velocity = Some(ins.gps_velocity(vel).expect("gps velocity"));
            }
            if let Some(alt) = r.baro_m {
                out.baro = Some(ins.baro(alt).expect("baro"));
            }
            if let Some(m) = r.mag {
                out.mag = Some(ins.mag(m).expect("mag"));
            }
            out
        }
    }
}
