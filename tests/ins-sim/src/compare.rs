//! Estimate-versus-reference comparison for the replay: read a truth CSV (our own column
//! layout, or a PX4 EKF2 change-indication file), match rows by time and summarise the
//! attitude, heading, position and velocity differences.

use crate::metrics::{attitude_angle_deg, wrap_deg};
use crate::replay::{ParseError, Row};
use crate::trajectory::to_euler;

/// Reads a reference file: either our [`crate::replay::HEADER`] layout or PX4's
/// `Timestamp,state[0..23],variance[0..23]` (q 0–3, velocity 4–6, position 7–9). EKF2 rows
/// from before its initialisation (identity attitude, all zeros) are dropped.
///
/// # Errors
/// The first malformed line.
pub fn parse_reference(text: &str) -> Result<Vec<Row>, ParseError> {
    let mut lines = text.lines().enumerate();
    let header = lines
        .next()
        .map(|(_, h)| h.trim().to_owned())
        .unwrap_or_default();
    let px4 = header.starts_with("Timestamp");
    let mut rows = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let values: Result<Vec<f64>, _> =
            line.split(',').map(|f| f.trim().parse::<f64>()).collect();
        let v = values.map_err(|_| ParseError {
            line: i + 1,
            reason: "not a number".into(),
        })?;
        let need = if px4 { 11 } else { 15 };
        if v.len() < need {
            return Err(ParseError {
                line: i + 1,
                reason: format!("expected at least {need} columns"),
            });
        }
        let g = |k: usize| v.get(k).copied().unwrap_or(0.0);
        let row = if px4 {
            Row {
                time_us: g(0) as u64,
                attitude: [g(1), g(2), g(3), g(4)],
                velocity_ned_mps: [g(5), g(6), g(7)],
                position_ned_m: [g(8), g(9), g(10)],
                gyro_bias_radps: [0.0; 3],
                accel_bias_z_mps2: 0.0,
            }
        } else {
            Row {
                time_us: g(0) as u64,
                attitude: [g(1), g(2), g(3), g(4)],
                velocity_ned_mps: [g(5), g(6), g(7)],
                position_ned_m: [g(8), g(9), g(10)],
                gyro_bias_radps: [g(11), g(12), g(13)],
                accel_bias_z_mps2: g(14),
            }
        };
        let uninitialised =
            px4 && row.attitude == [1.0, 0.0, 0.0, 0.0] && row.velocity_ned_mps == [0.0; 3];
        if !uninitialised {
            rows.push(row);
        }
    }
    Ok(rows)
}

/// Largest and final differences after the settling time.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Metrics {
    /// Compared rows.
    pub samples: usize,
    /// Max / final total attitude difference (deg).
    pub max_attitude_deg: f64,
    /// Final total attitude difference (deg).
    pub final_attitude_deg: f64,
    /// Max / final heading difference (deg, wrapped).
    pub max_heading_deg: f64,
    /// Final heading difference (deg).
    pub final_heading_deg: f64,
    /// Max roll/pitch difference (deg).
    pub max_tilt_deg: f64,
    /// Max / final position difference (m, 3-D).
    pub max_position_m: f64,
    /// Final position difference (m).
    pub final_position_m: f64,
    /// Max / final velocity difference (m/s, 3-D).
    pub max_velocity_mps: f64,
    /// Final velocity difference (m/s).
    pub final_velocity_mps: f64,
}

impl Metrics {
    /// One JSON object on one line.
    #[must_use]
    pub fn to_json(&self) -> String {
        format!(
            "{{\"samples\":{},\"max_attitude_deg\":{:.4},\"final_attitude_deg\":{:.4},\"max_heading_deg\":{:.4},\"final_heading_deg\":{:.4},\"max_tilt_deg\":{:.4},\"max_position_m\":{:.4},\"final_position_m\":{:.4},\"max_velocity_mps\":{:.4},\"final_velocity_mps\":{:.4}}}",
            self.samples,
            self.max_attitude_deg,
            self.final_attitude_deg,
            self.max_heading_deg,
            self.final_heading_deg,
            self.max_tilt_deg,
            self.max_position_m,
            self.final_position_m,
            self.max_velocity_mps,
            self.final_velocity_mps
        )
    }
}

fn norm(a: [f64; 3], b: [f64; 3]) -> f64 {
    let [x, y, z] = crate::zip3(a, b, |p, q| p - q);
    (x * x + y * y + z * z).sqrt()
}

/// Compares each reference row from `start_us + settle_s` on with the latest estimate at or
/// before its time (`estimates` sorted by time). `start_us` is the first reference time.
#[must_use]
pub fn compare(estimates: &[Row], reference: &[Row], settle_s: f64) -> Metrics {
    let mut m = Metrics::default();
    let Some(first) = reference.first() else {
        return m;
    };
    let from_us = first.time_us + (settle_s * 1e6) as u64;
    for r in reference.iter().filter(|r| r.time_us >= from_us) {
        let idx = estimates.partition_point(|e| e.time_us <= r.time_us);
        let Some(e) = idx.checked_sub(1).and_then(|i| estimates.get(i)) else {
            continue;
        };
        let att = attitude_angle_deg(e.attitude, r.attitude);
        let ee = to_euler(e.attitude);
        let re = to_euler(r.attitude);
        let heading = wrap_deg((ee[2] - re[2]).to_degrees());
        let tilt = wrap_deg((ee[0] - re[0]).to_degrees())
            .abs()
            .max((ee[1] - re[1]).to_degrees().abs());
        let pos = norm(e.position_ned_m, r.position_ned_m);
        let vel = norm(e.velocity_ned_mps, r.velocity_ned_mps);
        m.samples += 1;
        m.max_attitude_deg = m.max_attitude_deg.max(att);
        m.max_heading_deg = m.max_heading_deg.max(heading.abs());
        m.max_tilt_deg = m.max_tilt_deg.max(tilt);
        m.max_position_m = m.max_position_m.max(pos);
        m.max_velocity_mps = m.max_velocity_mps.max(vel);
        m.final_attitude_deg = att;
        m.final_heading_deg = heading;
        m.final_position_m = pos;
        m.final_velocity_mps = vel;
    }
    m
}
