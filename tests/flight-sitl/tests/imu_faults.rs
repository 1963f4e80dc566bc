//! IMU faults in flight (issue 13): the app rides through a short gap holding the last
//! command, then disarms with a reason and its own tone, asks for a re-probe, and never
//! restarts the motors without a fresh arm — here with the pilot holding hover throttle
//! the whole time and the sensor coming back.

#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

mod common;

use common::*;
use flight_app::app::{ImuFault, STALL_RIDE_THROUGH_MS};
use flight_app::outputs::Command;
use flight_app::supervisor::Decision;
use flight_sitl::{ImuInjection, PilotInput};

const FAULT_AT_S: f64 = 6.0;
const FAULT_END_S: f64 = 7.0;

fn faulted(injection: ImuInjection) -> flight_sitl::Sitl {
    fly(
        airframe_settings(),
        9.0,
        pilot(-1.0, move |t| PilotInput {
            imu: if (FAULT_AT_S..FAULT_END_S).contains(&t) {
                injection
            } else {
                ImuInjection::Healthy
            },
            ..cruise(-1.0)
        }),
    )
}

fn running(m: &[Command; 4]) -> bool {
    m.iter().all(|c| matches!(c, Command::Throttle(_)))
}

#[test]
fn an_imu_fault_in_flight_disarms_once_and_never_restarts_the_motors() {
    for (injection, fault, usable_samples) in [
        (ImuInjection::Stalled, ImuFault::Stalled, 0),
        (ImuInjection::ReadError, ImuFault::ReadError, 0),
        (ImuInjection::AllZero, ImuFault::AllZero, 0),
        // Frozen data is used until 20 identical samples have been seen.
        (ImuInjection::Frozen, ImuFault::Frozen, 19),
    ] {
        let sitl = faulted(injection);
        let s = &sitl.samples;
        let before = s.iter().rfind(|x| x.t_s < FAULT_AT_S).unwrap();
        assert!(
            before.out.armed && before.altitude_m > 0.5,
            "{injection:?}: flying"
        );
        let disarm = s
            .iter()
            .find(|x| x.out.decision == Decision::DisarmedSensorFault)
            .unwrap_or_else(|| panic!("{injection:?}: never disarmed"));
        let delay_ms = (disarm.t_s - before.t_s) * 1000.0;
        println!(
            "{injection:?}: disarmed {delay_ms:.0} ms after the last good sample at {:.2} m",
            disarm.altitude_m
        );
        let bound = f64::from(STALL_RIDE_THROUGH_MS) + f64::from(usable_samples) + 1.5;
        assert!(delay_ms <= bound, "{injection:?}: {delay_ms} ms");
        assert_eq!(disarm.imu_fault, Some(fault));
        assert!(disarm.imu_reprobe, "{injection:?}: re-probe requested");
        // Within the ride-through the motors ran on (held or flown).
        assert!(
            s.iter()
                .filter(|x| x.t_s > before.t_s && x.t_s < disarm.t_s)
                .all(|x| running(&x.motors)),
            "{injection:?}: motors held through the gap"
        );
        // The sensor-fault siren starts right away (3.5 kHz).
        assert!(
            s.iter()
                .filter(|x| x.t_s >= disarm.t_s && x.t_s < disarm.t_s + 0.05)
                .any(|x| x.tone_hz == 3500),
            "{injection:?}: siren"
        );
        // From the disarm on, nothing restarts the motors: the pilot never re-arms.
        assert!(
            s.iter()
                .filter(|x| x.t_s >= disarm.t_s)
                .all(|x| !running(&x.motors) && !x.out.armed),
            "{injection:?}: motors restarted without a new arm"
        );
        assert!(
            s.iter()
                .filter(|x| x.t_s > FAULT_END_S + 0.5)
                .all(|x| x.imu_fault.is_none()),
            "{injection:?}: the fault clears once the sensor is back"
        );
    }
}
