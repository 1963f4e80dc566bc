//! The co-simulation's plumbing with scripted MCUs: what reaches them, when, and what their
//! pins do to the world.

use super::machine::FakeMachine;
use super::*;
use crate::board::Input;
use crate::wire::{Drive, Outside, Pin};
use flight_app::control::mixer::QUAD_X;
use quad_sim::quad::QuadParams;

const PC4: Pin = Pin::new(2, 4);
const PC5: Pin = Pin::new(2, 5);

fn write(b: &mut FlightBoard, t: u64, register: u8, value: u8) {
    b.pin_driven(PC4, Drive::Low, t);
    b.spi_byte(1, register, t);
    b.spi_byte(1, value, t);
    b.pin_driven(PC4, Drive::High, t);
}

/// A flight "firmware": sets the MPU-9250 up once it answers, reads every sample on its
/// data-ready, and from 4.5 s holds every motor pin high (full throttle).
fn flight_behaviour() -> impl FnMut(&mut FlightBoard, u64, &[Input]) {
    let mut configured = false;
    move |b, now, due| {
        if !configured && now > 110_000_000 {
            write(b, now, 0x1A, 0x01);
            write(b, now, 0x37, 0x30);
            write(b, now, 0x38, 0x01);
            configured = true;
        }
        for i in due {
            if let Input::Pin {
                pin,
                level: true,
                at_ns,
            } = *i
                && pin == PC5
            {
                b.pin_driven(PC4, Drive::Low, at_ns + 2_000);
                b.spi_byte(1, 0x80 | 0x3B, at_ns + 2_000);
                for _ in 0..14 {
                    b.spi_byte(1, 0, at_ns + 2_000);
                }
                b.pin_driven(PC4, Drive::High, at_ns + 3_000);
            }
        }
        if now > 4_500_000_000 {
            for m in b.pins.motors {
                b.pin_driven(m, Drive::High, now);
            }
        }
    }
}

fn scenario(duration_s: f64) -> Scenario {
    let quad = QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X);
    Scenario::new(
        flight_app::settings::Settings::default(),
        quad,
        duration_s,
        Box::new(|_| PilotInput::default()),
    )
}

type TestWorld = World<FakeMachine<FlightBoard>, FakeMachine<ModuleBoard>>;

fn world(duration_s: f64, quantum_ns: u64) -> TestWorld {
    let s = scenario(duration_s);
    let config = WorldConfig {
        quantum_ns,
        ..WorldConfig::default()
    };
    let mut radios = Radios::new(7, 0.0);
    let protocol = Protocol::Brushed {
        frequency_hz: 32_000,
    };
    let fb = flight_board(&config, &mut radios, protocol, &s).unwrap();
    let mb = module_board(&mut radios).unwrap();
    let flight = FakeMachine::new(fb, flight_behaviour());
    let module = FakeMachine::new(mb, |_, _, _| {});
    World::new(s, config, radios, flight, module)
}

#[test]
fn data_ready_comes_at_the_imus_own_rate_and_every_sample_is_read() {
    let mut w = world(0.5, 20_000);
    w.run_until(1_200_000_000);
    let rises: Vec<u64> = w
        .flight
        .seen
        .iter()
        .filter_map(|i| match *i {
            Input::Pin {
                pin,
                level: true,
                at_ns,
            } if pin == PC5 => Some(at_ns),
            _ => None,
        })
        .collect();
    // From ≈ 110 ms: 1 kHz on the chip's clock, 300 ppm fast.
    assert!(
        rises.len() > 1_080 && rises.len() < 1_095,
        "{}",
        rises.len()
    );
    let period = rises[100] - rises[99];
    assert_eq!(period, 999_700, "1 ms / (1 + 300 ppm)");
    assert_eq!(w.flight.board().mpu.samples_missed(), 0);
    assert_eq!(
        w.loop_timing.unanswered() as usize,
        rises.len() - 1,
        "no motor ever moves"
    );
}

#[test]
fn ppm_frames_reach_the_module_edge_by_edge() {
    let mut w = world(0.5, 20_000);
    w.run_until(100_000_000);
    let falls: Vec<u64> = w
        .module
        .seen
        .iter()
        .filter_map(|i| match *i {
            Input::Pin {
                pin,
                level: false,
                at_ns,
            } if pin == crate::board::module::PINS.ppm_in => Some(at_ns),
            _ => None,
        })
        .collect();
    // Frames at 0, 22.5, 45, 67.5 ms: 9 falling edges each (then the one at 90 ms).
    assert_eq!(falls.iter().filter(|t| **t < 90_000_000).count(), 36);
    assert_eq!(falls[9], handset::PPM_FRAME_NS);
    assert!(falls.windows(2).all(|w| w[1] > w[0]));
}

#[test]
fn the_motor_pins_fly_the_quad_and_the_records_are_flight_sitls() {
    let mut w = world(1.0, 50_000);
    w.run_to_end();
    let sitl = w.finish();
    // One sample per ms of the scenario (after the 4 s warm-up).
    assert!(
        (sitl.samples.len() as i64 - 1_000).abs() <= 1,
        "{}",
        sitl.samples.len()
    );
    let last = sitl.samples.last().unwrap();
    assert!(
        last.altitude_m > 2.0,
        "full throttle climbs: {}",
        last.altitude_m
    );
    assert!(last.out.armed, "motors turning read as armed");
    assert_eq!(sitl.watchdog_resets.flight, 0);
    let first = &sitl.samples[0];
    assert!(first.t_s.abs() < 2e-3);
    assert_eq!(first.altitude_m, 0.0);
    assert!(!first.out.armed);
    // The arming edge shows as the supervisor's decision.
    assert!(
        sitl.samples
            .iter()
            .any(|s| s.out.decision == flight_app::supervisor::Decision::Armed)
    );
}

#[test]
fn the_body_to_ned_field_rotation() {
    // Level, facing north: body = NED.
    let level = rotate_to_body([1.0, 0.0, 0.0, 0.0], EARTH_FIELD_NED_UT);
    assert_eq!(level, EARTH_FIELD_NED_UT);
    // Yawed 90° right (facing east): north is to the body's left (−y).
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let east = rotate_to_body([h, 0.0, 0.0, h], [1.0, 0.0, 0.0]);
    assert!((east[0]).abs() < 1e-12 && (east[1] + 1.0).abs() < 1e-12);
}
