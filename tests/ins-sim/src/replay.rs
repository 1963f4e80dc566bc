//! Log replay in the PX4 ECL replay format (`testdata/px4-ecl/README.md`): parse the
//! sensor lines, drive an [`Ins`] with them (GPS origin = first fix), produce one estimate
//! row per IMU sample, and compare estimates with a truth or a PX4 EKF2 history.

use flight_app::estimation::ins::aiding::AidingConfig;
use flight_app::estimation::ins::{Config, Ins};
use flight_app::estimation::quaternion;

/// Output CSV header (issue 7).
pub const HEADER: &str = "time_us,qw,qx,qy,qz,vn,ve,vd,pn,pe,pd,gbx,gby,gbz,abz";

/// One sensor line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Record {
    /// IMU: specific force (m/s²) then rate (rad/s), body FRD.
    Imu {
        /// Time (µs).
        time_us: u64,
        /// Specific force.
        accel_mps2: [f32; 3],
        /// Angular rate.
        gyro_radps: [f32; 3],
    },
    /// Magnetometer (gauss, body FRD).
    Mag {
        /// Time (µs).
        time_us: u64,
        /// Field.
        field_gauss: [f32; 3],
    },
    /// Barometric altitude AMSL (m).
    Baro {
        /// Time (µs).
        time_us: u64,
        /// Altitude.
        altitude_m: f32,
    },
    /// GPS fix.
    Gps {
        /// Time (µs).
        time_us: u64,
        /// Latitude (deg).
        lat_deg: f64,
        /// Longitude (deg).
        lon_deg: f64,
        /// Altitude AMSL (m).
        alt_m: f64,
        /// Velocity NED (m/s).
        velocity_ned_mps: [f32; 3],
    },
}

/// Why a line could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    /// 1-based line number.
    pub line: usize,
    /// What was wrong.
    pub reason: String,
}

impl std::fmt::Display for ParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line == 0 {
            // Not one line's fault (an empty file).
            f.write_str(&self.reason)
        } else {
            write!(f, "line {}: {}", self.line, self.reason)
        }
    }
}

/// Physical bounds of the sensor values a log may hold: wider than any sensor on a
/// multirotor reports (MEMS gyros saturate at 35–70 rad/s, accelerometers at 16–32 g), so
/// a value outside is a corrupt or mis-scaled log, not flight.
pub mod limits {
    /// |specific force| per axis, m/s² (≈ 100 g).
    pub const ACCEL_MPS2: f64 = 1000.0;
    /// |rate| per axis, rad/s (≈ 5700 deg/s).
    pub const GYRO_RADPS: f64 = 100.0;
    /// |field| per axis, gauss (the earth's is < 0.7).
    pub const MAG_GAUSS: f64 = 20.0;
    /// Altitude AMSL, m (baro and GPS): Dead Sea shore to well above any multirotor.
    pub const ALTITUDE_M: (f64, f64) = (-1000.0, 50_000.0);
    /// |GPS velocity| per axis, m/s.
    pub const VELOCITY_MPS: f64 = 500.0;
}

fn within(
    values: &[f64],
    bound: f64,
    what: &str,
    unit: &str,
    line: usize,
) -> Result<(), ParseError> {
    match values.iter().find(|v| v.abs() > bound) {
        Some(v) => Err(ParseError {
            line,
            reason: format!(
                "{what} {} {unit} is beyond ±{bound} {unit}: not a plausible reading",
                if v.abs() >= 1e6 {
                    format!("{v:e}")
                } else {
                    v.to_string()
                }
            ),
        }),
        None => Ok(()),
    }
}

fn in_range(
    v: f64,
    (lo, hi): (f64, f64),
    what: &str,
    unit: &str,
    line: usize,
) -> Result<(), ParseError> {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(ParseError {
            line,
            reason: format!("{what} {v} {unit} is outside {lo}..={hi} {unit}"),
        })
    }
}

impl std::error::Error for ParseError {}

fn numbers<const N: usize>(fields: &[&str], line: usize) -> Result<[f64; N], ParseError> {
    if fields.len() != N {
        return Err(ParseError {
            line,
            reason: format!("expected {N} values, found {}", fields.len()),
        });
    }
    let mut out = [0.0; N];
    for (o, f) in out.iter_mut().zip(fields) {
        *o = f
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| ParseError {
                line,
                reason: format!("not a finite number: {f:?}"),
            })?;
    }
    Ok(out)
}

/// Parses the sensor file; kinds other than imu/mag/baro/gps (airspeed, landed, …) are
/// skipped. Empty lines are ignored.
///
/// # Errors
/// The first malformed line: not a number (NaN and infinities included), a time earlier
/// than the line before, a value beyond [`limits`]; or a file with no IMU record.
pub fn parse_sensors(text: &str) -> Result<Vec<Record>, ParseError> {
    let mut out = Vec::new();
    let mut last_time_us = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let fields: Vec<&str> = raw.trim().split(',').collect();
        let [t, kind, values @ ..] = fields.as_slice() else {
            continue;
        };
        if t.is_empty() {
            continue;
        }
        let time_us: u64 = t.trim().parse().map_err(|_| ParseError {
            line,
            reason: format!("bad time {t:?}"),
        })?;
        // The replay integrates in file order: a step back in time would be a negative dt.
        if time_us < last_time_us {
            return Err(ParseError {
                line,
                reason: format!("time goes backwards: {time_us} µs after {last_time_us} µs"),
            });
        }
        last_time_us = time_us;
        let f = |v: f64| v as f32;
        match kind.trim() {
            "imu" => {
                let [ax, ay, az, gx, gy, gz] = numbers::<6>(values, line)?;
                within(
                    &[ax, ay, az],
                    limits::ACCEL_MPS2,
                    "specific force",
                    "m/s²",
                    line,
                )?;
                within(&[gx, gy, gz], limits::GYRO_RADPS, "rate", "rad/s", line)?;
                out.push(Record::Imu {
                    time_us,
                    accel_mps2: [f(ax), f(ay), f(az)],
                    gyro_radps: [f(gx), f(gy), f(gz)],
                });
            }
            "mag" => {
                let [x, y, z] = numbers::<3>(values, line)?;
                within(
                    &[x, y, z],
                    limits::MAG_GAUSS,
                    "magnetic field",
                    "gauss",
                    line,
                )?;
                out.push(Record::Mag {
                    time_us,
                    field_gauss: [f(x), f(y), f(z)],
                });
            }
            "baro" => {
                let [alt] = numbers::<1>(values, line)?;
                in_range(alt, limits::ALTITUDE_M, "baro altitude", "m", line)?;
                out.push(Record::Baro {
                    time_us,
                    altitude_m: f(alt),
                });
            }
            "gps" => {
                let [alt_mm, lon, lat, vn, ve, vd] = numbers::<6>(values, line)?;
                in_range(lat * 1e-7, (-90.0, 90.0), "latitude", "deg", line)?;
                in_range(lon * 1e-7, (-180.0, 180.0), "longitude", "deg", line)?;
                in_range(alt_mm * 1e-3, limits::ALTITUDE_M, "GPS altitude", "m", line)?;
                within(
                    &[vn, ve, vd],
                    limits::VELOCITY_MPS,
                    "GPS velocity",
                    "m/s",
                    line,
                )?;
                out.push(Record::Gps {
                    time_us,
                    lat_deg: lat * 1e-7,
                    lon_deg: lon * 1e-7,
                    alt_m: alt_mm * 1e-3,
                    velocity_ned_mps: [f(vn), f(ve), f(vd)],
                });
            }
            _ => {}
        }
    }
    // Nothing to integrate: an empty file, or one of another format.
    if !out.iter().any(|r| matches!(r, Record::Imu { .. })) {
        return Err(ParseError {
            line: 0,
            reason: "no IMU records (empty file, or not the PX4 replay format \"time_us,imu,ax,ay,az,gx,gy,gz\")".into(),
        });
    }
    Ok(out)
}

/// One estimate (or truth) row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Time (µs).
    pub time_us: u64,
    /// Attitude body FRD → NED.
    pub attitude: [f64; 4],
    /// Velocity NED (m/s).
    pub velocity_ned_mps: [f64; 3],
    /// Position NED (m).
    pub position_ned_m: [f64; 3],
    /// Gyro bias (rad/s).
    pub gyro_bias_radps: [f64; 3],
    /// z accel bias (m/s²).
    pub accel_bias_z_mps2: f64,
}

impl Row {
    /// The CSV line (without newline) in [`HEADER`] order.
    #[must_use]
    pub fn to_csv(&self) -> String {
        let [qw, qx, qy, qz] = self.attitude;
        let [vn, ve, vd] = self.velocity_ned_mps;
        let [pn, pe, pd] = self.position_ned_m;
        let [bx, by, bz] = self.gyro_bias_radps;
        format!(
            "{},{qw:.7},{qx:.7},{qy:.7},{qz:.7},{vn:.5},{ve:.5},{vd:.5},{pn:.4},{pe:.4},{pd:.4},{bx:.7},{by:.7},{bz:.7},{:.6}",
            self.time_us, self.accel_bias_z_mps2
        )
    }
}

/// Replay settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Filter tuning.
    pub config: Config,
    /// Aiding policy.
    pub aiding: AidingConfig,
    /// Magnetic declination (deg, east positive) used for the earth field.
    pub declination_deg: f32,
    /// The sensors' noise figures (`--noise`, `--tuning`), if known: the filter then
    /// derives its noise terms from them ([`crate::noise::told`]).
    pub noise: Option<flight_app::estimation::ins::SensorNoise>,
}

impl Default for Options {
    /// Tuning for the PX4 SITL recordings: gyro noise density from the logs' own noise at
    /// rest (0.004 rad/s per 4 ms sample); accelerometer noise density set far above the
    /// at-rest 0.04 m/s² so ground contact after landing (forces the kinematic model does not
    /// know) does not drag the velocity away from GPS; GPS and baro variances of a plausible
    /// receiver and baro; magnetometer noise of 0.02 G on a 0.2 G horizontal field (~6° per
    /// 250 Hz sample), trusting GPS more for heading during manoeuvres.
    fn default() -> Self {
        Self {
            config: Config {
                gyro_noise_psd: [1e-7; 3],
                accel_noise_psd: 1e-2,
                gyro_bias_walk_psd: 1e-8,
                accel_bias_walk_psd: 1e-5,
                gps_horizontal_var_m2: 0.1,
                gps_vertical_var_m2: 1.0,
                gps_velocity_var_m2ps2: 0.05,
                baro_var_m2: 0.05,
                mag_var: 4e-4,
                earth_field_ned: [0.2, 0.0, 0.43],
                gate_sigma: 5.0,
                gyro_bias_limit_radps: 0.35,
                accel_bias_limit_mps2: 2.0,
                initial_std: [1.0, 0.5, 0.02, 0.01, 0.1],
            },
            aiding: AidingConfig::default(),
            declination_deg: 0.0,
            noise: None,
        }
    }
}

/// Flat-earth NED of a fix relative to the origin fix (as the Tau Labs replay: R = 6378137 m
/// plus the origin altitude).
#[must_use]
pub fn ned_from_origin(
    origin: (f64, f64, f64),
    lat_deg: f64,
    lon_deg: f64,
    alt_m: f64,
) -> [f64; 3] {
    let (lat0, lon0, alt0) = origin;
    let r = 6_378_137.0 + alt0;
    [
        (lat_deg - lat0).to_radians() * r,
        (lon_deg - lon0).to_radians() * r * lat0.to_radians().cos(),
        -(alt_m - alt0),
    ]
}

/// The records in the order they are fused: each measurement right after the IMU sample
/// nearest to it in time (the later one on a tie), IMU samples and measurements otherwise
/// in file order. A measurement stamped with an IMU sample's time but listed before it
/// would otherwise be fused against the estimate one IMU period old: under a rocking turn
/// the frame accelerates at up to 5 m/s², so at 500 Hz that alone was ≈ 10 mm/s of GPS
/// velocity mismatch, and the velocity error settled at 6 mm/s RMS instead of 0.8
/// (`tests/ins_sweep.rs`).
#[must_use]
pub fn schedule(records: &[Record]) -> Vec<Record> {
    let time = |r: &Record| match *r {
        Record::Imu { time_us, .. }
        | Record::Mag { time_us, .. }
        | Record::Baro { time_us, .. }
        | Record::Gps { time_us, .. } => time_us,
    };
    let imu_times: Vec<u64> = records
        .iter()
        .filter(|r| matches!(r, Record::Imu { .. }))
        .map(time)
        .collect();
    // after[k]: the measurements fused after IMU sample k; `before`: those nearest to no
    // IMU sample before the first one.
    let mut after: Vec<Vec<Record>> = vec![Vec::new(); imu_times.len()];
    let mut before = Vec::new();
    for r in records.iter().filter(|r| !matches!(r, Record::Imu { .. })) {
        let t = time(r);
        let next = imu_times.partition_point(|&ti| ti < t);
        let nearest = match (next.checked_sub(1), imu_times.get(next)) {
            (Some(prev), Some(&tn)) => {
                let tp = imu_times.get(prev).copied().unwrap_or(0);
                if t - tp < tn - t { prev } else { next }
            }
            (Some(prev), None) => prev,
            (None, _) => next,
        };
        match after.get_mut(nearest) {
            Some(slot) => slot.push(*r),
            None => before.push(*r),
        }
    }
    let mut out = before;
    let imus = records.iter().filter(|r| matches!(r, Record::Imu { .. }));
    for (r, slot) in imus.zip(after.iter_mut()) {
        out.push(*r);
        out.append(slot);
    }
    out
}

/// Runs the records through a fresh INS. The filter aligns on the first IMU sample once a
/// magnetometer sample has been seen (roll/pitch from accel, yaw from mag); GPS and baro are
/// fused once the first fix has set the origin (baro offset = baro − GPS altitude then).
/// Rows before alignment hold the identity attitude and zeros, as EKF2's do.
#[must_use]
pub fn run(records: &[Record], options: &Options) -> Vec<Row> {
    run_with_progress(records, options, |_| {})
}

/// [`run`], calling `progress` with the number of records done every 10 000 records (for a
/// host tool's progress bar).
#[must_use]
pub fn run_with_progress(
    records: &[Record],
    options: &Options,
    mut progress: impl FnMut(usize),
) -> Vec<Row> {
    let told = options
        .noise
        .map(|n| crate::noise::told(options, &n, records));
    let options = told.as_ref().unwrap_or(options);
    let records = schedule(records);
    let mut ins = Ins::new(options.config, options.aiding);
    let mut rows = Vec::new();
    let mut last_imu_us: Option<u64> = None;
    let mut last_mag: Option<[f32; 3]> = None;
    let mut last_baro: Option<f32> = None;
    let mut aligned = false;
    let mut origin: Option<(f64, f64, f64)> = None;
    let mut baro_offset_m = 0.0_f32;
    for (i, record) in records.iter().enumerate() {
        if i % 10_000 == 0 {
            progress(i);
        }
        match *record {
            Record::Imu {
                time_us,
                accel_mps2,
                gyro_radps,
            } => {
                if !aligned {
                    if let Some(mag) = last_mag {
                        aligned = align(&mut ins, options, accel_mps2, mag);
                    }
                } else if let Some(prev) = last_imu_us {
                    let dt = (time_us.saturating_sub(prev)) as f32 * 1e-6;
                    if dt > 0.0 {
                        let _ = ins.predict(gyro_radps, accel_mps2, dt.min(0.1));
                    }
                }
                last_imu_us = Some(time_us);
                rows.push(row(time_us, aligned.then(|| ins.state())));
            }
            Record::Mag { field_gauss, .. } => {
                last_mag = Some(field_gauss);
                if aligned {
                    let _ = ins.mag(field_gauss);
                }
            }
            Record::Baro { altitude_m, .. } => {
                last_baro = Some(altitude_m);
                if aligned && origin.is_some() {
                    let _ = ins.baro(altitude_m - baro_offset_m);
                }
            }
            Record::Gps {
                lat_deg,
                lon_deg,
                alt_m,
                velocity_ned_mps,
                ..
            } => {
                if !aligned {
                    continue;
                }
                let o = match origin {
                    Some(o) => o,
                    None => {
                        // The first fix is the origin; the baro reading at that moment is
                        // the vertical origin of the baro altitudes.
                        baro_offset_m = last_baro.unwrap_or(alt_m as f32);
                        *origin.insert((lat_deg, lon_deg, alt_m))
                    }
                };
                let [n, e, d] = ned_from_origin(o, lat_deg, lon_deg, alt_m);
                let _ = ins.gps_position([n as f32, e as f32, d as f32], false);
                let _ = ins.gps_velocity(velocity_ned_mps);
            }
        }
    }
    rows
}

fn align(ins: &mut Ins, options: &Options, accel: [f32; 3], mag: [f32; 3]) -> bool {
    // Earth field: the first reading levelled with the accelerometer's tilt gives the
    // horizontal and vertical magnitudes; the declination turns the horizontal part.
    let [roll, pitch] = flight_app::estimation::ins::tilt_from_accel(accel);
    let level = quaternion::from_euler(roll, pitch, 0.0);
    let [mn, me, md] = quaternion::body_to_ned_vector(level, mag);
    let h = (mn * mn + me * me).sqrt();
    let d = options.declination_deg.to_radians();
    let mut config = options.config;
    config.earth_field_ned = [h * d.cos(), h * d.sin(), md];
    *ins = Ins::new(config, options.aiding);
    ins.align(accel, mag, [0.0; 3]).is_ok()
}

fn row(time_us: u64, state: Option<flight_app::estimation::ins::State>) -> Row {
    let Some(s) = state else {
        return Row {
            time_us,
            attitude: [1.0, 0.0, 0.0, 0.0],
            velocity_ned_mps: [0.0; 3],
            position_ned_m: [0.0; 3],
            gyro_bias_radps: [0.0; 3],
            accel_bias_z_mps2: 0.0,
        };
    };
    Row {
        time_us,
        attitude: s.attitude.map(f64::from),
        velocity_ned_mps: s.velocity_ned_mps.map(f64::from),
        position_ned_m: s.position_ned_m.map(f64::from),
        gyro_bias_radps: s.gyro_bias_radps.map(f64::from),
        accel_bias_z_mps2: f64::from(s.accel_bias_z_mps2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn imu(time_us: u64) -> Record {
        Record::Imu {
            time_us,
            accel_mps2: [0.0, 0.0, -9.8],
            gyro_radps: [0.0; 3],
        }
    }

    fn baro(time_us: u64) -> Record {
        Record::Baro {
            time_us,
            altitude_m: 0.0,
        }
    }

    #[test]
    fn each_measurement_follows_the_imu_sample_nearest_in_time() {
        // GIVEN measurements listed before the IMU sample of their instant, one between two
        // samples nearer the earlier, one on a tie, one before the first and after the last
        let file = [
            baro(0),
            imu(1000),
            baro(3000),
            imu(3000),
            baro(3900),
            baro(5000),
            imu(7000),
            baro(9000),
        ];
        // WHEN scheduled
        let order: Vec<(bool, u64)> = schedule(&file)
            .iter()
            .map(|r| match *r {
                Record::Imu { time_us, .. } => (true, time_us),
                Record::Baro { time_us, .. } => (false, time_us),
                _ => (false, u64::MAX),
            })
            .collect();
        // THEN each comes right after its nearest IMU sample (the later one on a tie)
        assert_eq!(
            order,
            [
                (true, 1000),
                (false, 0),
                (true, 3000),
                (false, 3000),
                (false, 3900),
                (true, 7000),
                (false, 5000),
                (false, 9000),
            ]
        );
    }
}
