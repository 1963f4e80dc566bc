//! Telling the estimator the sensors' noise: the `--noise gyro=G,accel=A,mag=M,baro=B,
//! gps_pos=P,gps_alt=H,gps_vel=V` list (any subset) and the `--tuning FILE` that holds the
//! whole set, turned into a `SensorNoise`; and applying it to replay options (IMU period
//! measured from the log). The derivation itself is flight-core's
//! (`Config::with_sensor_noise`, `AidingConfig::for_known_noise`).

use flight_app::estimation::ins::SensorNoise;

use crate::replay::{Options, Record};

/// The keys, in the order they are documented, with their units.
pub const KEYS: [(&str, &str); 7] = [
    ("gyro", "rad/s"),
    ("accel", "m/s²"),
    ("mag", "magnetometer unit (gauss in PX4 logs)"),
    ("baro", "m"),
    ("gps_pos", "m"),
    ("gps_alt", "m"),
    ("gps_vel", "m/s"),
];

fn slot<'a>(noise: &'a mut SensorNoise, key: &str) -> Option<&'a mut Option<f32>> {
    Some(match key {
        "gyro" => &mut noise.gyro_radps,
        "accel" => &mut noise.accel_mps2,
        "mag" => &mut noise.mag,
        "baro" => &mut noise.baro_m,
        "gps_pos" => &mut noise.gps_position_m,
        "gps_alt" => &mut noise.gps_altitude_m,
        "gps_vel" => &mut noise.gps_velocity_mps,
        _ => return None,
    })
}

/// Adds `key=value` items (separated by commas, whitespace or new lines; `#` starts a
/// comment) to `noise`.
///
/// # Errors
/// An unknown key, a repeated key, or a value that is not a finite number > 0.
pub fn parse_into(noise: &mut SensorNoise, text: &str) -> Result<(), String> {
    let mut seen: Vec<String> = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("");
        for item in line
            .split([',', ' ', '\t'])
            .filter(|s| !s.trim().is_empty())
        {
            let (key, value) = item
                .split_once('=')
                .ok_or_else(|| format!("{item:?}: expected key=value"))?;
            let key = key.trim();
            let names: Vec<&str> = KEYS.iter().map(|(k, _)| *k).collect();
            let target = slot(noise, key)
                .ok_or_else(|| format!("unknown noise key {key:?} (keys: {})", names.join(", ")))?;
            if seen.iter().any(|s| s == key) {
                return Err(format!("{key} given twice"));
            }
            seen.push(key.to_string());
            let v: f32 = value
                .trim()
                .parse()
                .ok()
                .filter(|v: &f32| v.is_finite() && *v > 0.0)
                .ok_or_else(|| {
                    format!("{key}={value}: the 1σ noise must be a finite number > 0")
                })?;
            *target = Some(v);
        }
    }
    Ok(())
}

/// The `--noise` list (any subset).
///
/// # Errors
/// As [`parse_into`].
pub fn parse_noise(list: &str) -> Result<SensorNoise, String> {
    let mut noise = SensorNoise::default();
    parse_into(&mut noise, list)?;
    Ok(noise)
}

/// A `--tuning` file: the whole set, every key once.
///
/// # Errors
/// As [`parse_into`], or a key missing.
pub fn parse_tuning(text: &str) -> Result<SensorNoise, String> {
    let noise = parse_noise(text)?;
    let mut probe = noise;
    let missing: Vec<&str> = KEYS
        .iter()
        .map(|(k, _)| *k)
        .filter(|k| slot(&mut probe, k).is_some_and(|v| v.is_none()))
        .collect();
    if missing.is_empty() {
        Ok(noise)
    } else {
        Err(format!(
            "the tuning file must give every figure; missing: {}",
            missing.join(", ")
        ))
    }
}

/// `--tuning` first, then `--noise` on top (a figure in both: the list wins).
///
/// # Errors
/// As [`parse_tuning`] and [`parse_noise`].
pub fn combine(
    tuning_text: Option<&str>,
    noise_list: Option<&str>,
) -> Result<Option<SensorNoise>, String> {
    let mut noise = match tuning_text {
        Some(t) => Some(parse_tuning(t).map_err(|e| format!("--tuning: {e}"))?),
        None => None,
    };
    if let Some(list) = noise_list {
        let over = parse_noise(list).map_err(|e| format!("--noise: {e}"))?;
        let base = noise.get_or_insert_with(SensorNoise::default);
        for (k, _) in KEYS {
            let mut o = over;
            if let Some(Some(v)) = slot(&mut o, k).map(|v| *v)
                && let Some(t) = slot(base, k)
            {
                *t = Some(v);
            }
        }
    }
    Ok(noise)
}

/// Mean IMU sample period of the log (s); `None` with fewer than two IMU samples.
#[must_use]
pub fn imu_period_s(records: &[Record]) -> Option<f64> {
    let times: Vec<u64> = records
        .iter()
        .filter_map(|r| match r {
            Record::Imu { time_us, .. } => Some(*time_us),
            _ => None,
        })
        .collect();
    let (first, last) = (times.first()?, times.last()?);
    let n = times.len().checked_sub(1).filter(|n| *n > 0)?;
    Some(last.saturating_sub(*first) as f64 * 1e-6 / n as f64)
}

/// `options` with the filter told `noise`: its noise terms derived from the figures at the
/// log's IMU period and the known-noise aiding policy. Unchanged without IMU samples.
#[must_use]
pub fn told(options: &Options, noise: &SensorNoise, records: &[Record]) -> Options {
    let Some(dt) = imu_period_s(records) else {
        return *options;
    };
    Options {
        config: options.config.with_sensor_noise(noise, dt as f32),
        aiding: options.aiding.for_known_noise(),
        ..*options
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_subset_parses_and_the_rest_stays_unknown() {
        let n = parse_noise("gyro=0.001, mag=10,gps_vel=0.05").unwrap();
        assert_eq!(n.gyro_radps, Some(0.001));
        assert_eq!(n.mag, Some(10.0));
        assert_eq!(n.gps_velocity_mps, Some(0.05));
        assert_eq!(n.accel_mps2, None);
        assert_eq!(n.baro_m, None);
    }

    #[test]
    fn nonsense_is_refused_with_a_reason() {
        assert!(parse_noise("gyro=-1").unwrap_err().contains("> 0"));
        assert!(parse_noise("gyro=nan").is_err());
        assert!(
            parse_noise("gyr=1")
                .unwrap_err()
                .contains("unknown noise key")
        );
        assert!(parse_noise("gyro").unwrap_err().contains("key=value"));
        assert!(parse_noise("gyro=1,gyro=2").unwrap_err().contains("twice"));
    }

    #[test]
    fn tuning_file_needs_the_whole_set_and_noise_overrides_it() {
        let file = "# reference scenario\ngyro=1e-3\naccel=1e-3\nmag=10\nbaro=1e-3\n\
                    gps_pos=1e-3 gps_alt=1e-3\ngps_vel=1e-3\n";
        let n = parse_tuning(file).unwrap();
        assert_eq!(n.gps_altitude_m, Some(1e-3));
        let err = parse_tuning("gyro=1e-3").unwrap_err();
        assert!(
            err.contains("missing: accel, mag, baro, gps_pos, gps_alt, gps_vel"),
            "{err}"
        );
        let both = combine(Some(file), Some("mag=20")).unwrap().unwrap();
        assert_eq!(both.mag, Some(20.0));
        assert_eq!(both.gyro_radps, Some(1e-3));
        assert_eq!(combine(None, None).unwrap(), None);
    }

    #[test]
    fn told_options_use_the_logs_imu_period() {
        let imu = |t| Record::Imu {
            time_us: t,
            accel_mps2: [0.0, 0.0, -9.8],
            gyro_radps: [0.0; 3],
        };
        let records = [imu(0), imu(4000), imu(8000)];
        let n = parse_noise("gyro=0.01").unwrap();
        let o = told(&Options::default(), &n, &records);
        assert!((o.config.gyro_noise_psd[0] - 1e-4 * 0.004).abs() < 1e-10);
        assert!(o.aiding.settled_gyro_bias_walk_psd.is_some());
        assert_eq!(o.config.mag_var, Options::default().config.mag_var);
    }
}
