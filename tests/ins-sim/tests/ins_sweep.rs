//! Issue 32's acceptance: the INS from any start and through a rocking turn, as the replay
//! runs it told the sensors' true noise (`ins_sim::sweep`; the README's `ins-figures` table
//! is these runs, `cargo run --release -p ins-sim --bin ins-figures -- write`).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)] // test code

use ins_sim::sweep::{self, limits};

#[test]
fn from_every_heading_and_tilt_the_heading_converges() {
    // GIVEN a still frame at each of 24 headings, 15° apart, level and tilted 15° and 30°
    // WHEN the replay runs 60 s of its log, told the noise
    let starts = sweep::static_sweep();
    assert_eq!(
        starts.len(),
        sweep::HEADINGS_DEG.len() * sweep::TILTS_DEG.len()
    );
    // THEN every start's heading is within 1° by 10 s and 0.05° at 60 s, roll/pitch within
    // 0.05°
    for s in &starts {
        println!("{s:?}");
        let name = format!("heading {}°, tilt {}°", s.heading_deg, s.tilt_deg);
        assert!(
            s.heading_10s_deg <= limits::HEADING_10S_DEG,
            "{name}: {}° at 10 s",
            s.heading_10s_deg
        );
        assert!(
            s.heading_below_1deg_s.is_some_and(|t| t <= 10.0),
            "{name}: {:?}",
            s.heading_below_1deg_s
        );
        assert!(
            s.heading_60s_deg <= limits::HEADING_60S_DEG,
            "{name}: {}° at 60 s",
            s.heading_60s_deg
        );
        assert!(
            s.tilt_60s_deg <= limits::TILT_60S_DEG,
            "{name}: tilt {}°",
            s.tilt_60s_deg
        );
    }
}

#[test]
fn rocking_while_turning_keeps_the_velocity() {
    // GIVEN yawing at 5 °/s with a 0.1 Hz pitch rocking from 30 s (tilts to ≈ 32°)
    let r = sweep::rock_and_turn();
    println!("{r:?}");
    // THEN the velocity error over the last 20 s stays within the README's figure, which is
    // half the C INS's final 0.004 m/s
    assert!(r.velocity_rms_mps <= limits::ROCK_VELOCITY_RMS_MPS, "{r:?}");
    assert!(r.attitude_rms_deg <= limits::ROCK_ATTITUDE_RMS_DEG, "{r:?}");
    assert!(
        r.velocity_final_mps <= sweep::c_reference::ROCK_VELOCITY_MPS,
        "{r:?}"
    );
}

#[test]
fn the_noise_list_is_valid() {
    assert!(ins_sim::noise::parse_noise(sweep::NOISE).is_ok());
    assert!(sweep::told().noise.is_some());
}
