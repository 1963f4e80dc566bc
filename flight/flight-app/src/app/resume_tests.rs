//! The resume decision: fresh and stale records, broken CRCs, the arm switch and the link.

use super::*;
use crate::app::LinkInput;
use crate::gains;
use crate::pipeline::ImuSample;
use crate::supervisor::{Decision, FlightMode, Sticks};

/// A record of a frame flying at 20 s: armed, in the air, attitude mode.
fn flying(written_ms: u32) -> FlightState {
    FlightState {
        written_ms,
        armed: true,
        in_air: true,
        failsafe: false,
        mode: FlightMode::Attitude,
        hover_throttle: 0.42,
        attitude: [1.0, 0.0, 0.0, 0.0],
        gyro_bias_radps: [0.001, -0.002, 0.0005],
    }
}

/// The blocks a board keeps, with the gains of the factory settings.
struct Blocks {
    state: [u32; STATE_WORDS],
    gains: [u32; GAINS_WORDS],
    fault: [u32; FAULT_WORDS],
    feed: [u32; FEED_WORDS],
}

impl Blocks {
    fn new(state: FlightState) -> Self {
        let settings = Settings::default();
        let setup = from_settings(&settings).unwrap();
        let controllers = gains::design(&setup.control).unwrap();
        Self {
            state: state.encode(),
            gains: encode_gains(&settings, controllers.designs()).unwrap(),
            fault: [0; FAULT_WORDS],
            feed: [0; FEED_WORDS],
        }
    }

    fn kept(&self) -> Kept<'_> {
        Kept {
            state: &self.state,
            gains: &self.gains,
            fault: &self.fault,
            feed: &self.feed,
        }
    }
}

#[test]
fn every_block_round_trips_and_a_flipped_bit_fails_its_crc() {
    let state = FlightState {
        attitude: [0.996, 0.087, 0.0, 0.0],
        ..flying(20_000)
    };
    assert_eq!(FlightState::decode(&state.encode()), Some(state));
    let fault = Fault {
        reason: FaultReason::HardFault,
        at_ms: 20_003,
        address: 0x0801_2345,
    };
    assert_eq!(Fault::decode(&fault.encode()), Some(fault));
    assert_eq!(decode_feed(&encode_feed(19_990)), Some(19_990));
    let b = Blocks::new(state);
    let (settings, designs) = decode_gains(&b.gains).unwrap();
    assert_eq!(settings, Settings::default());
    let setup = from_settings(&settings).unwrap();
    let designed = gains::design(&setup.control).unwrap();
    // The same gains, bit for bit: the rebuilt controllers equal the designed ones.
    assert_eq!(gains::rebuild(&setup.control, designs), designed);
    for bit in [0, 37, 100, 31 * STATE_WORDS as u32] {
        let mut words = state.encode();
        let (w, b) = ((bit / 32) as usize % STATE_WORDS, bit % 32);
        words[w] ^= 1 << b;
        assert_eq!(FlightState::decode(&words), None, "bit {bit}");
    }
    let mut gains = b.gains;
    gains[GAINS_WORDS / 2] ^= 0x100;
    assert_eq!(decode_gains(&gains), None);
    // Power-up RAM: whatever it holds, never a record.
    assert_eq!(FlightState::decode(&[0xA5A5_A5A5; STATE_WORDS]), None);
    assert_eq!(decode_feed(&[0, 0]), None);
}

#[test]
fn a_fresh_record_after_a_watchdog_or_panic_reset_resumes() {
    // Watchdog: the last feed at 19.9 s, the IWDG's longest timeout (552 ms at 17 kHz)
    // after it is the latest the reset can have come: 0.45 s after the record.
    let mut b = Blocks::new(flying(20_000));
    b.feed = encode_feed(19_900);
    let r = plan(ResetCause::Watchdog, &b.kept()).unwrap();
    assert_eq!(r.state, flying(20_000));
    assert_eq!(r.fault, None);
    // Panic: the handler's stamp 3 ms after the record.
    let mut b = Blocks::new(flying(20_000));
    let panic = Fault {
        reason: FaultReason::Panic,
        at_ms: 20_003,
        address: 0,
    };
    b.fault = panic.encode();
    assert_eq!(
        plan(ResetCause::Software, &b.kept()).unwrap().fault,
        Some(panic)
    );
}

#[test]
fn stale_broken_grounded_or_power_on_records_boot_cold() {
    let mut b = Blocks::new(flying(20_000));
    b.feed = encode_feed(20_500);
    // 20.5 s + 552 ms is 1.05 s after the record: stale.
    assert_eq!(
        plan(ResetCause::Watchdog, &b.kept()).unwrap_err(),
        ColdBoot::Stale
    );
    // A software reset with no fault stamp: the reset's time is unknown.
    assert_eq!(
        plan(ResetCause::Software, &b.kept()).unwrap_err(),
        ColdBoot::Stale
    );
    // Only a watchdog or a handler's reset resumes.
    b.feed = encode_feed(20_000);
    for cause in [ResetCause::PowerOn, ResetCause::Pin, ResetCause::Other] {
        assert_eq!(
            plan(cause, &b.kept()).unwrap_err(),
            ColdBoot::NotAFaultReset
        );
    }
    assert!(plan(ResetCause::Watchdog, &b.kept()).is_ok());
    // A bad CRC in the state or the gains.
    b.state[3] ^= 1;
    assert_eq!(
        plan(ResetCause::Watchdog, &b.kept()).unwrap_err(),
        ColdBoot::NoState
    );
    let mut b = Blocks::new(flying(20_000));
    b.feed = encode_feed(20_000);
    b.gains[5] ^= 1;
    assert_eq!(
        plan(ResetCause::Watchdog, &b.kept()).unwrap_err(),
        ColdBoot::NoGains
    );
    // Disarmed, or armed on the ground.
    for (armed, in_air) in [(false, true), (true, false), (false, false)] {
        let mut b = Blocks::new(FlightState {
            armed,
            in_air,
            ..flying(20_000)
        });
        b.feed = encode_feed(20_000);
        assert_eq!(
            plan(ResetCause::Watchdog, &b.kept()).unwrap_err(),
            ColdBoot::NotInTheAir
        );
    }
}

fn resumed_app() -> FlightApp {
    let mut b = Blocks::new(flying(20_000));
    b.feed = encode_feed(19_950);
    let r = plan(ResetCause::Watchdog, &b.kept()).unwrap();
    FlightApp::resume(Settings::default(), &r, 0).unwrap()
}

/// Hovering level, as the IMU reads it (with the sensor's wiggle: identical samples are the
/// frozen-data fault).
fn level(t: u32) -> ImuSample {
    crate::app::tests::resting(t)
}

fn link(arm_switch: Option<bool>) -> LinkInput {
    LinkInput {
        up: true,
        sticks: Sticks {
            throttle: 0.45,
            ..Sticks::default()
        },
        arm_switch,
        mode_channel: -1.0,
    }
}

#[test]
fn a_resumed_app_drives_the_motors_before_the_link_and_arms_when_it_shows_the_switch_on() {
    let mut app = resumed_app();
    assert!(app.armed(), "motors enabled from the first sample");
    assert_eq!(app.resumed(), Some(None));
    let step = app.on_imu_sample(1, &level(1));
    assert!(
        step.motors
            .iter()
            .all(|m| matches!(m, crate::outputs::Command::Throttle(t) if *t > 0.3)),
        "hover-level motors at once: {:?}",
        step.motors
    );
    let out = app.last_output().unwrap();
    assert!(out.failsafe, "in failsafe until the link speaks");
    // The link back, the arm switch on: armed in the recorded mode.
    app.link_input = link(Some(true));
    app.on_imu_sample(2, &level(2));
    let out = app.last_output().unwrap();
    assert_eq!(out.decision, Decision::Resumed);
    assert!(out.armed && !out.failsafe);
    assert_eq!(out.mode, FlightMode::Attitude);
}

#[test]
fn a_resumed_app_disarms_on_the_switch_off_and_lands_without_a_link() {
    let mut app = resumed_app();
    app.link_input = link(Some(false));
    app.on_imu_sample(1, &level(1));
    assert_eq!(
        app.last_output().unwrap().decision,
        Decision::DisarmedByPilot
    );
    assert!(!app.armed());
    // No link at all: the failsafe flies on (descending), motors running.
    let mut app = resumed_app();
    for t in 1..2_000 {
        app.on_imu_sample(t, &level(t));
    }
    let out = app.last_output().unwrap();
    assert!(out.armed && out.failsafe);
}

#[test]
fn the_app_keeps_its_state_and_gains_for_the_firmware() {
    let mut app = FlightApp::new(Settings::default(), 0).unwrap();
    let mut gains = [0; GAINS_WORDS];
    assert!(app.keep_resume_gains(&mut gains), "gains at boot");
    assert!(!app.keep_resume_gains(&mut gains), "once per change");
    let (settings, _) = decode_gains(&gains).unwrap();
    assert_eq!(settings, Settings::default());
    let mut side = app.take_loop_side().unwrap();
    let words = side.resume_state_due(0).expect("the first state");
    let state = FlightState::decode(&words).unwrap();
    assert!(!state.armed);
    assert!(
        side.resume_state_due(5).is_none(),
        "not before the refresh period"
    );
    assert!(side.resume_state_due(10).is_some());
}
