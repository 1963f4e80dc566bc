//! The flight controller's ULog logs (`flight_app::logging`) read for replay: the
//! settings from the parameter messages (the initial ones and every change), the sensor
//! topics in the order the flight core fed them to its estimator, and the estimate it
//! flew on. Two replays use them:
//!
//! - [`as_flown`]: the flight core's own estimate stage (`pipeline::Estimator`) fed the
//!   logged samples, with the logged settings, in the logged order, restarted where the
//!   log says the loop restarted — the estimate the flight computed, to the bit when the
//!   log holds every sample (`log.profile full`);
//! - [`records`]: the sensor samples as the PX4-format replay's records, for the research
//!   INS of [`crate::replay`] with `--noise`/`--tuning`.
//!
//! Every reading of the file's bytes returns an error for anything unreadable: not ULog,
//! a topic whose format differs from this build's (a log of another version), a parameter
//! the settings refuse.

use flight_app::estimation::ins::State;
use flight_app::logging::{
    self, Estimate, Profile, SensorBaro, SensorGps, SensorImu, TOPICS, imu_flags,
};
use flight_app::pipeline::{Estimator, ImuSample, from_settings};
use flight_app::settings::{Kind, PARAMS, Settings, Value, handles};
use taulink_ulog::{Message, Reader, Record as UlogRecord, Scalar};

use crate::replay::{Record, Row};

/// What a flight log holds, in file order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Item {
    /// An IMU sample the estimator took.
    Imu(SensorImu),
    /// A baro altitude handed to it.
    Baro(SensorBaro),
    /// A NAV-PVT handed to it.
    Gps(SensorGps),
    /// The estimate the loop flew on.
    Estimate(Estimate),
    /// The loop restarted with a new setup (the estimator starts afresh).
    Restart,
    /// Settings changed (the index into [`FlightLog::settings`]).
    Settings(usize),
}

/// A flight log, read.
#[derive(Debug, Clone)]
pub struct FlightLog {
    /// The settings at the start, then after each change.
    pub settings: Vec<Settings>,
    /// The items in file order.
    pub items: Vec<Item>,
    /// Dropout marks (lost data), ms each.
    pub dropouts: Vec<u16>,
    /// The file was cut inside a message (a power cut while writing).
    pub truncated: bool,
}

impl FlightLog {
    /// The log profile it was written with.
    pub fn profile(&self) -> Profile {
        let settings = self.settings.first().cloned().unwrap_or_default();
        Profile::from_index(settings.get(handles::LOG_PROFILE))
    }
}

/// Whether `bytes` start like a ULog file.
pub fn is_ulog(bytes: &[u8]) -> bool {
    bytes.starts_with(&taulink_ulog::MAGIC)
}

/// The setting change a parameter message makes (its name with `.` for `/`).
fn parameter(name: &str, value: Scalar) -> Result<(&'static str, Value), String> {
    let dotted = name.replace('/', ".");
    let p = PARAMS
        .iter()
        .find(|p| p.name == dotted)
        .ok_or_else(|| format!("parameter {name}: no such setting in this build"))?;
    let value = match (p.kind, value) {
        (Kind::F32 { .. }, Scalar::F32(v)) => Value::F32(v),
        // Whole numbers travel as int32_t bits (ULog has no uint32_t parameters).
        (Kind::U32 { .. } | Kind::Choice(_), Scalar::Int(v)) => Value::U32(v as i32 as u32),
        _ => return Err(format!("parameter {name}: wrong type {value:?}")),
    };
    Ok((p.name, value))
}

fn apply(settings: &mut Settings, changes: &[(&'static str, Value)]) -> Result<(), String> {
    if changes.is_empty() {
        return Ok(());
    }
    settings
        .set_many(changes)
        .map_err(|e| format!("logged settings refused: {e}"))
}

/// Reads a flight log.
///
/// # Errors
/// Not ULog; a malformed message; incompatible flags; a topic whose format is not this
/// build's; a parameter this build does not have or whose value it refuses.
pub fn read(bytes: &[u8]) -> Result<FlightLog, String> {
    let mut reader = Reader::new(bytes).map_err(|e| e.to_string())?;
    let mut initial: Vec<(&'static str, Value)> = Vec::new();
    let mut settings = vec![];
    let mut ids: Vec<Option<usize>> = Vec::new();
    let mut items = Vec::new();
    let mut dropouts = Vec::new();
    for message in reader.by_ref() {
        let (offset, message) = message.map_err(|e| e.to_string())?;
        match message {
            Message::Format(f) => {
                if let Some(t) = TOPICS.iter().find(|t| t.name == f.name) {
                    let text = format!("{}:{}", f.name, fields_text(&f));
                    if text != t.format {
                        return Err(format!(
                            "topic {}: its format differs from this build's (a log of another version)",
                            f.name
                        ));
                    }
                }
            }
            Message::Parameter { key, value } => {
                let change = parameter(key.name, key.scalar(value).map_err(|e| e.to_string())?)?;
                if settings.is_empty() && items.is_empty() {
                    initial.push(change);
                } else {
                    let mut s: Settings = settings.last().cloned().unwrap_or_default();
                    apply(&mut s, &[change])?;
                    settings.push(s);
                    items.push(Item::Settings(settings.len() - 1));
                }
            }
            Message::Subscription { msg_id, name, .. } => {
                if settings.is_empty() {
                    let mut s = Settings::default();
                    apply(&mut s, &initial)?;
                    settings.push(s);
                }
                let id = usize::from(msg_id);
                if ids.len() <= id {
                    ids.resize(id + 1, None);
                }
                if let Some(slot) = ids.get_mut(id) {
                    *slot = TOPICS.iter().position(|t| t.name == name);
                }
            }
            Message::Data { msg_id, data } => {
                let topic = ids.get(usize::from(msg_id)).copied().flatten();
                if let Some(item) = data_item(topic, data, offset)? {
                    items.push(item);
                }
            }
            Message::Logging { text, .. } if text.starts_with(b"new setup installed") => {
                items.push(Item::Restart);
            }
            Message::Dropout { duration_ms } => dropouts.push(duration_ms),
            _ => {}
        }
    }
    if settings.is_empty() {
        let mut s = Settings::default();
        apply(&mut s, &initial)?;
        settings.push(s);
    }
    Ok(FlightLog {
        settings,
        items,
        dropouts,
        truncated: reader.truncated(),
    })
}

fn fields_text(f: &taulink_ulog::format::Format) -> String {
    f.fields()
        .map(|d| match d.ty.array {
            Some(n) => format!("{}[{n}] {};", d.ty.name, d.name),
            None => format!("{} {};", d.ty.name, d.name),
        })
        .collect()
}

fn data_item(topic: Option<usize>, data: &[u8], offset: usize) -> Result<Option<Item>, String> {
    let Some(name) = topic.and_then(|i| TOPICS.get(i)).map(|t| t.name) else {
        return Ok(None);
    };
    let bad = |e: taulink_ulog::Error| format!("offset {offset}: {name}: {e}");
    Ok(Some(match name {
        n if n == SensorImu::NAME => Item::Imu(SensorImu::decode(data).map_err(bad)?),
        n if n == SensorBaro::NAME => Item::Baro(SensorBaro::decode(data).map_err(bad)?),
        n if n == SensorGps::NAME => Item::Gps(SensorGps::decode(data).map_err(bad)?),
        n if n == Estimate::NAME => Item::Estimate(Estimate::decode(data).map_err(bad)?),
        _ => return Ok(None),
    }))
}

/// One estimate of a replay, after an IMU sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Replayed {
    /// Time, µs.
    pub time_us: u64,
    /// Attitude body → NED.
    pub attitude: [f32; 4],
    /// The INS state while it flies.
    pub ins: Option<State>,
}

/// Replays the log through the flight core's own estimate stage: one estimate per logged
/// IMU sample.
///
/// # Errors
/// Settings that make no setup.
pub fn as_flown(log: &FlightLog) -> Result<Vec<Replayed>, String> {
    let estimator_for = |s: &Settings| -> Result<(Estimator, f32), String> {
        let setup =
            from_settings(s).map_err(|e| format!("logged settings make no setup: {e:?}"))?;
        let c = setup.loop_config;
        Ok((Estimator::new(c.estimator, c.attitude_filter), c.ts_s))
    };
    let mut settings = log.settings.first().cloned().unwrap_or_default();
    let (mut estimator, mut ts_s) = estimator_for(&settings)?;
    let mut out = Vec::new();
    for item in &log.items {
        match item {
            Item::Imu(r) => {
                let sample = ImuSample {
                    gyro_radps: r.gyro_radps,
                    accel_mps2: r.accel_mps2,
                    mag: (r.flags & imu_flags::MAG != 0).then_some(r.mag),
                };
                let corrects = r.flags & imu_flags::ACCEL_CORRECTS != 0;
                let armed = r.flags & imu_flags::ARMED != 0;
                let _ = estimator.update(&sample, corrects, armed, ts_s);
                out.push(Replayed {
                    time_us: r.timestamp,
                    attitude: estimator.attitude(),
                    ins: estimator.ins_state(),
                });
            }
            Item::Baro(r) => estimator.baro(r.altitude_m),
            Item::Gps(r) => {
                let _ = estimator.gps(&logging::gps_from_record(r));
            }
            Item::Settings(i) => {
                if let Some(s) = log.settings.get(*i) {
                    settings = s.clone();
                }
            }
            Item::Restart => (estimator, ts_s) = estimator_for(&settings)?,
            Item::Estimate(_) => {}
        }
    }
    Ok(out)
}

impl Replayed {
    /// As a row of the replay's CSV (zeros where the INS does not fly).
    pub fn row(&self) -> Row {
        let ins = self.ins;
        Row {
            time_us: self.time_us,
            attitude: self.attitude.map(f64::from),
            velocity_ned_mps: ins.map_or([0.0; 3], |s| s.velocity_ned_mps.map(f64::from)),
            position_ned_m: ins.map_or([0.0; 3], |s| s.position_ned_m.map(f64::from)),
            gyro_bias_radps: ins.map_or([0.0; 3], |s| s.gyro_bias_radps.map(f64::from)),
            accel_bias_z_mps2: ins.map_or(0.0, |s| f64::from(s.accel_bias_z_mps2)),
        }
    }
}

/// How a replay compares with the estimates logged in flight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Check {
    /// Pairs compared (replayed and logged, in order).
    pub compared: usize,
    /// Pairs whose attitude, and INS velocity and position where logged, are bit-identical.
    pub identical: usize,
    /// The largest difference of a quaternion component.
    pub max_quaternion_diff: f32,
}

/// Compares a replay with the logged estimates, pair by pair in order.
pub fn compare(replayed: &[Replayed], logged: &[Estimate]) -> Check {
    let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
    let mut check = Check {
        compared: 0,
        identical: 0,
        max_quaternion_diff: 0.0,
    };
    for (r, l) in replayed.iter().zip(logged) {
        check.compared += 1;
        let q = r.attitude.iter().zip(&l.q);
        let diff = q.clone().map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        check.max_quaternion_diff = check.max_quaternion_diff.max(diff);
        let (v, p) = match r.ins {
            Some(s) => (s.velocity_ned_mps, s.position_ned_m),
            None => ([f32::NAN; 3], [f32::NAN; 3]),
        };
        let ins_same = v.iter().zip(&l.velocity_ned_mps).all(|(a, b)| same(*a, *b))
            && p.iter().zip(&l.position_ned_m).all(|(a, b)| same(*a, *b));
        if q.clone().all(|(a, b)| same(*a, *b)) && ins_same {
            check.identical += 1;
        }
    }
    check
}

/// The estimates the flight logged, one per loop (in the full profile).
pub fn logged(log: &FlightLog) -> Vec<Estimate> {
    log.items
        .iter()
        .filter_map(|i| match i {
            Item::Estimate(e) => Some(*e),
            _ => None,
        })
        .collect()
}

/// The sensor samples as the PX4-format replay's records (magnetometer in its logged
/// units, GPS fixes that are 3-D and valid only).
pub fn records(log: &FlightLog) -> Vec<Record> {
    let mut out = Vec::new();
    for item in &log.items {
        match *item {
            Item::Imu(r) => {
                out.push(Record::Imu {
                    time_us: r.timestamp,
                    accel_mps2: r.accel_mps2,
                    gyro_radps: r.gyro_radps,
                });
                if r.flags & imu_flags::MAG != 0 {
                    out.push(Record::Mag {
                        time_us: r.timestamp,
                        field_gauss: r.mag,
                    });
                }
            }
            Item::Baro(r) => out.push(Record::Baro {
                time_us: r.timestamp,
                altitude_m: r.altitude_m,
            }),
            Item::Gps(r) if r.fix_type == 3 && r.flags & 1 != 0 => out.push(Record::Gps {
                time_us: r.timestamp,
                lat_deg: f64::from(r.lat_e7) * 1e-7,
                lon_deg: f64::from(r.lon_e7) * 1e-7,
                alt_m: f64::from(r.h_msl_mm) * 1e-3,
                velocity_ned_mps: r.vel_ned_mmps.map(|v| v as f32 * 1e-3),
            }),
            _ => {}
        }
    }
    out
}
