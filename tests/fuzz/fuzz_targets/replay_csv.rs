//! The replay tool's CSV readers (`ins_sim::replay::parse_sensors` for PX4 sensor logs,
//! `ins_sim::compare::parse_reference` for truth / EKF2 histories) on fuzzed text.
//!
//! Invariants: parsing returns records or a line-numbered error, never panics; an error
//! names a line that exists; there are never more records than lines; an IMU record printed
//! back as a CSV line parses to the same record.
#![no_main]

use ins_sim::compare::parse_reference;
use ins_sim::replay::{Record, parse_sensors};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let lines = text.lines().count();
    match parse_sensors(text) {
        Ok(records) => {
            assert!(records.len() <= lines);
            for record in records {
                if let Record::Imu {
                    time_us,
                    accel_mps2: [ax, ay, az],
                    gyro_radps: [gx, gy, gz],
                } = record
                {
                    let line = format!("{time_us},imu,{ax},{ay},{az},{gx},{gy},{gz}");
                    let back = parse_sensors(&line).expect("a printed IMU line parses");
                    // Compare bit patterns: a NaN reading is not equal to itself.
                    assert_eq!(format!("{back:?}"), format!("{:?}", [record]));
                }
            }
        }
        Err(e) => assert!(e.line <= lines, "{e}"),
    }
    match parse_reference(text) {
        Ok(rows) => assert!(rows.len() <= lines),
        Err(e) => assert!(e.line >= 1 && e.line <= lines, "{e}"),
    }
});
