//! Issue 31's flight log through the firmware-in-the-loop world: what the flight core
//! records, drained and encoded as the logging task does, read back as ULog; a 60 s hover
//! logged at the full profile replays through the flight core's estimate stage
//! (`ins_sim::flight_log::as_flown`, what `replay FILE.ulg` runs) to the estimate flown,
//! bit for bit; the profiles' contents.

#![allow(clippy::unwrap_used)]

use flight_app::logging::{Profile, TOPICS};
use flight_app::settings::handles;
use flight_sitl::runner::{Kind, Options, run_kind};
use ins_sim::flight_log;
use taulink_ulog::{Message, Reader};

fn hover_log(profile: Profile, gps: bool, duration_s: f64) -> Vec<u8> {
    let mut o = Options::for_kind(Kind::Hover, gps).unwrap();
    o.duration_s = Some(duration_s);
    o.settings
        .put(handles::LOG_PROFILE, profile.index())
        .unwrap();
    let outcome = run_kind(Kind::Hover, &o).unwrap();
    assert_eq!(outcome.sitl.flight_logs.len(), 1, "one boot, one log");
    outcome.sitl.flight_logs.into_iter().next().unwrap()
}

/// A 60 s hover at the full profile, replayed: every logged estimate equals the replay's.
fn replays_bit_for_bit(gps: bool) {
    let bytes = hover_log(Profile::Full, gps, 60.0);
    let log = flight_log::read(&bytes).unwrap();
    assert_eq!(log.profile(), Profile::Full);
    assert!(log.dropouts.is_empty(), "nothing lost: {:?}", log.dropouts);
    assert!(!log.truncated);
    let replayed = flight_log::as_flown(&log).unwrap();
    let logged = flight_log::logged(&log);
    // 1 kHz for the 60 s and the warm-up before it.
    assert!(replayed.len() > 60_000, "{} samples", replayed.len());
    assert_eq!(replayed.len(), logged.len());
    let check = flight_log::compare(&replayed, &logged);
    println!("{check:?}");
    assert_eq!(check.identical, logged.len(), "{check:?}");
    assert_eq!(check.max_quaternion_diff, 0.0);
    if gps {
        let ins_samples = replayed.iter().filter(|r| r.ins.is_some()).count();
        assert!(ins_samples > 55_000, "the INS flew: {ins_samples}");
    }
}

#[test]
fn a_hover_at_the_full_profile_replays_to_the_flown_estimate_bit_for_bit() {
    replays_bit_for_bit(false);
}

#[test]
fn a_hover_with_gps_and_the_ins_replays_bit_for_bit_too() {
    replays_bit_for_bit(true);
}

#[test]
fn a_log_holds_the_definitions_every_setting_and_its_profile_topics() {
    let bytes = hover_log(Profile::Flight, false, 5.0);
    let mut formats = Vec::new();
    let mut params = 0;
    let mut per_topic = vec![0usize; TOPICS.len()];
    let mut armed = false;
    let mut first_data = None;
    for m in Reader::new(&bytes).unwrap() {
        let (offset, m) = m.unwrap();
        match m {
            Message::Format(f) => formats.push(f.name),
            Message::Parameter { .. } => params += 1,
            Message::Data { msg_id, .. } => {
                first_data.get_or_insert(offset);
                per_topic[usize::from(msg_id)] += 1;
            }
            Message::Logging { text, .. } => armed |= text == b"armed",
            _ => {}
        }
    }
    let names: Vec<&str> = TOPICS.iter().map(|t| t.name).collect();
    assert_eq!(formats, names);
    assert_eq!(params, telemetry::settings::COUNT);
    assert!(armed, "the arming is a logged string");
    let count = |name: &str| per_topic[names.iter().position(|n| *n == name).unwrap()];
    // The flight profile over ≈ 9 s of boot, warm-up and scenario: IMU at 20 Hz,
    // estimate at 10 Hz, every fifth of the baro's 50 Hz.
    let imu = count("sensor_imu");
    let estimate = count("estimate");
    assert!((160..=200).contains(&imu), "{imu}");
    assert!((2 * estimate).abs_diff(imu) <= 2, "{estimate} vs {imu}");
    assert!(count("sensor_baro").abs_diff(estimate) <= 5);
    assert_eq!(count("sensor_gps"), 0, "no receiver");
    assert!(count("link_stats") > 10);
}

#[test]
fn the_off_profile_logs_only_the_definitions() {
    let bytes = hover_log(Profile::Off, false, 2.0);
    let data = Reader::new(&bytes)
        .unwrap()
        .filter(|m| matches!(m, Ok((_, Message::Data { .. } | Message::Logging { .. }))))
        .count();
    assert_eq!(data, 0);
}

#[test]
fn ulog_csv_lays_a_log_out_as_ulog2csv_does() {
    let bytes = hover_log(Profile::Flight, false, 2.0);
    let tables = flight_sitl::ulog_csv::tables(&bytes).unwrap();
    let estimates = flight_log::logged(&flight_log::read(&bytes).unwrap());
    let text = &tables["estimate_0.csv"];
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "timestamp,q[0],q[1],q[2],q[3],euler_deg[0],euler_deg[1],euler_deg[2],\
         velocity_ned_mps[0],velocity_ned_mps[1],velocity_ned_mps[2],position_ned_m[0],\
         position_ned_m[1],position_ned_m[2],gyro_bias_radps[0],gyro_bias_radps[1],\
         gyro_bias_radps[2],accel_bias_z_mps2,altitude_m,climb_mps,source"
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), estimates.len());
    let last = rows.last().unwrap().split(',').collect::<Vec<_>>();
    let e = estimates.last().unwrap();
    assert_eq!(last[0], e.timestamp.to_string());
    assert_eq!(last[1].parse::<f32>().unwrap(), e.q[0]);
    // No GPS: the complementary filter flies and the INS fields are NaN.
    assert_eq!(last[8], "NaN");
    assert!(!tables.contains_key("sensor_gps_0.csv"), "no data, no file");
}

#[test]
fn overlay_frames_follow_the_log_at_the_video_rate_and_are_transparent_around_the_drawing() {
    let bytes = hover_log(Profile::Link, true, 4.0);
    let frames = flight_sitl::overlay::frames(&bytes, 25.0).unwrap();
    let span = frames.last().unwrap().t_s - frames[0].t_s;
    assert_eq!(frames.len(), (span * 25.0).round() as usize + 1);
    assert!((frames[1].t_s - frames[0].t_s - 0.04).abs() < 1e-6);
    let last = frames.last().unwrap();
    let status = last.status.unwrap();
    assert!(status.armed, "hovering");
    let (left, right) = flight_sitl::overlay::texts(last);
    assert!(left[0].starts_with("ALT"), "{left:?}");
    assert!(right[0].starts_with("ARMED"), "{right:?}");
    assert!(right.iter().any(|l| l.starts_with("LQ 100 %")), "{right:?}");
    let rgba = flight_sitl::overlay::draw(last).unwrap();
    let (w, h) = flight_sitl::overlay::SIZE;
    assert_eq!(rgba.len(), (w * h * 4) as usize);
    let alpha = |x: u32, y: u32| rgba[((y * w + x) * 4 + 3) as usize];
    assert_eq!(alpha(w / 2, h - 5), 0, "transparent below");
    let drawn = rgba.chunks_exact(4).filter(|p| p[3] == 255).count();
    assert!(
        drawn > 2_000 && drawn < (w * h / 10) as usize,
        "{drawn} pixels drawn"
    );
    assert!(flight_sitl::overlay::frames(&bytes, 0.0).is_err());
}
