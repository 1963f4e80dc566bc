//! The firmware-in-the-loop world itself: both applications boot on virtual chips, the link
//! comes up through the real driver, the module relays the flight side's telemetry, and
//! both independent watchdogs stay fed in normal flight.
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

mod common;

use flight_app::outputs::Command;
use flight_sitl::scenario::default_airframe;
use flight_sitl::{
    BootCause, End, FlashInjection, PilotInput, RadioInjection, Scenario, Sitl, WatchdogResets, run,
};
use telemetry::link::RateMode;

#[test]
fn both_ends_boot_once_link_and_stay_fed_on_the_ground() {
    let (quad, settings) = default_airframe();
    let sitl = run(Scenario::new(
        settings,
        quad,
        3.0,
        Box::new(|_| PilotInput::default()),
    ));
    println!(
        "boots {:?}, resets {:?}, samples {}, link up {}, module rx {}",
        sitl.boots,
        sitl.watchdog_resets,
        sitl.samples.len(),
        sitl.samples.iter().filter(|s| s.link_up).count(),
        sitl.module_rx.len()
    );
    assert_eq!(sitl.watchdog_resets.flight, 0);
    assert_eq!(sitl.watchdog_resets.module, 0);
    let ends: Vec<_> = sitl.boots.iter().map(|b| (b.end, b.cause)).collect();
    assert!(ends.contains(&(End::Flight, BootCause::PowerOn)));
    assert!(ends.contains(&(End::Module, BootCause::PowerOn)));
    assert_eq!(sitl.boots.len(), 2);
    assert!(sitl.samples.iter().all(|s| s.flight_up && s.link_up));
    assert!(
        !sitl.module_rx.is_empty(),
        "telemetry reaches the module's phone relay"
    );
}

/// Take-off and cruise, then `then` from 5 s.
fn hover_then(then: impl Fn(f64) -> PilotInput + 'static) -> Box<dyn FnMut(f64) -> PilotInput> {
    common::pilot(-1.0, move |t| {
        let mut p = common::cruise(-1.0);
        if t >= 5.0 {
            p = PilotInput {
                throttle: p.throttle,
                ..then(t)
            };
        }
        p
    })
}

fn fly_at(rate: RateMode, seconds: f64, pilot: Box<dyn FnMut(f64) -> PilotInput>) -> Sitl {
    let (quad, settings) = default_airframe();
    run(Scenario {
        rate,
        ..Scenario::new(settings, quad, seconds, pilot)
    })
}

/// Issue 12/13: a link loss in the air, at every rate mode, is a failsafe descent and never
/// a watchdog reset of either end (the follower's hooks keep the link task checked in
/// while it searches).
#[test]
fn a_link_cut_at_every_rate_is_a_failsafe_never_a_reset() {
    for rate in RateMode::ALL {
        let sitl = fly_at(
            rate,
            9.0,
            hover_then(|t| PilotInput {
                link_cut: t < 8.0,
                ..common::cruise(-1.0)
            }),
        );
        let s = &sitl.samples;
        let failsafe = s.iter().find(|x| x.out.failsafe).map(|x| x.t_s);
        println!(
            "{rate:?}: resets {:?}, failsafe at {failsafe:?}, boots {}",
            sitl.watchdog_resets,
            sitl.boots.len()
        );
        assert!(
            s.iter().filter(|x| x.t_s < 5.0).all(|x| x.link_up),
            "{rate:?}"
        );
        assert_eq!(sitl.watchdog_resets, WatchdogResets::default(), "{rate:?}");
        assert_eq!(sitl.boots.len(), 2, "{rate:?}");
        let failsafe = failsafe.unwrap();
        assert!((5.0..5.6).contains(&failsafe), "{rate:?}: {failsafe}");
        assert!(s.iter().all(|x| x.flight_up));
    }
}

/// `flight_powered` off and on is a power-on boot after the modelled boot time: the app's
/// state is lost (a live setting change not saved is gone) and the stored settings load.
#[test]
fn a_power_cycle_boots_again_from_the_stored_settings() {
    use flight_app::report::f32_value;
    use flight_app::settings::PARAMS;
    use telemetry::messages::SettingChange;
    let (quad, settings) = default_airframe();
    let id = PARAMS
        .iter()
        .position(|p| p.name == "failsafe.descent_mps")
        .unwrap() as u16;
    // A keyed pair: the phone signs its change with the link's change key (which a phone
    // that proved the phrase gets from the module).
    let key = telemetry::link::LinkKey::from_bytes(*b"module key, sitl");
    let sitl = run(Scenario {
        module_settings: Some(module_core::settings::Settings {
            link_key: Some(key),
            ..module_core::settings::Settings::default()
        }),
        setting_changes: vec![SettingChange {
            id,
            value: f32_value(0.9),
        }],
        ..Scenario::new(
            settings,
            quad,
            3.0,
            Box::new(|t| PilotInput {
                flight_powered: !(1.0..1.5).contains(&t),
                ..PilotInput::default()
            }),
        )
    });
    let flight_boots: Vec<_> = sitl.boots.iter().filter(|b| b.end == End::Flight).collect();
    println!("{flight_boots:?}");
    assert_eq!(flight_boots.len(), 2);
    assert_eq!(flight_boots[1].cause, BootCause::PowerOn);
    let boot_s = flight_boots[1].t_s;
    let expected = 1.5 + flight_sitl::flight_end::FLIGHT_BOOT_MS as f64 * 1e-3;
    assert!((boot_s - expected).abs() < 0.01, "{boot_s}");
    let s = &sitl.samples;
    assert!(s.iter().filter(|x| x.t_s < 1.0).all(|x| x.flight_up));
    assert!(
        s.iter()
            .filter(|x| (1.01..boot_s).contains(&x.t_s))
            .all(|x| !x.flight_up && x.motors == [Command::Stopped; 4])
    );
    assert!(
        s.iter()
            .filter(|x| x.t_s > boot_s + 0.01)
            .all(|x| x.flight_up)
    );
    assert_eq!(sitl.watchdog_resets, WatchdogResets::default());
    // The change reached the app before the cut and was saved (a phone's change is saved as
    // the console's `save` is): the reboot loads 0.9, not the factory's 0.7.
    assert_eq!(
        sitl.settings
            .get(flight_app::settings::handles::FAILSAFE_DESCENT_MPS),
        0.9
    );
}

/// Corrupted settings flash at the first boot: the flight controller boots on the factory
/// settings, reports the problem at boot and never arms. The stored bind went with the
/// settings: an unbound controller runs no link (binding is explicit), so nothing reaches
/// the module until the owner binds again. (The blocker's telemetry bit and console line
/// are checked in flight-core's app tests.)
#[test]
fn corrupted_settings_boot_on_factory_settings_and_refuse_to_arm() {
    let (quad, settings) = default_airframe();
    let sitl = run(Scenario {
        flight_flash: FlashInjection::Corrupted(11),
        gps: None,
        ..Scenario::new(
            settings,
            quad,
            4.0,
            common::pilot(-1.0, |_| common::cruise(-1.0)),
        )
    });
    let boot = sitl.boots.iter().find(|b| b.end == End::Flight).unwrap();
    assert!(boot.settings_error);
    let s = &sitl.samples;
    assert!(s.iter().all(|x| !x.out.armed && x.altitude_m < 0.05));
    assert!(s.iter().all(|x| !x.link_up), "no bind, no link");
    assert!(sitl.module_rx.is_empty());
    assert_eq!(sitl.watchdog_resets, WatchdogResets::default());
}

/// Issue 13: the handset's input stops at the module (PPM wire pulled) in the air: the
/// module stops sending channels after its input timeout and the flight side is in
/// failsafe within 1 s; nothing resets.
#[test]
fn a_pulled_handset_wire_gives_failsafe_within_a_second() {
    let sitl = fly_at(
        RateMode::F250,
        7.0,
        hover_then(|_| PilotInput {
            handset_connected: false,
            ..common::cruise(-1.0)
        }),
    );
    let failsafe = sitl.samples.iter().find(|x| x.out.failsafe).unwrap().t_s;
    println!("failsafe at {failsafe:.3} s (input stopped at 5 s)");
    assert!((5.0..6.0).contains(&failsafe), "{failsafe}");
    assert_eq!(sitl.watchdog_resets, WatchdogResets::default());
}

/// Radio faults on either end (nIRQ stuck low, a brown-out of the module's chip, SPI bus
/// errors) are ridden through by both applications: no watchdog reset, the link back.
#[test]
fn radio_faults_are_ridden_through_without_a_reset() {
    let sitl = fly_at(
        RateMode::F250,
        10.0,
        hover_then(|t| PilotInput {
            flight_radio: if (5.0..5.3).contains(&t) {
                RadioInjection::IrqStuckLow
            } else if (7.0..7.2).contains(&t) {
                RadioInjection::SpiErrors
            } else {
                RadioInjection::Healthy
            },
            module_radio: if (6.0..6.2).contains(&t) {
                RadioInjection::BrownOut
            } else if (8.0..8.3).contains(&t) {
                RadioInjection::IrqStuckHigh
            } else {
                RadioInjection::Healthy
            },
            ..common::cruise(-1.0)
        }),
    );
    let s = &sitl.samples;
    println!(
        "resets {:?}, boots {}, link down {:.2} s",
        sitl.watchdog_resets,
        sitl.boots.len(),
        s.iter().filter(|x| !x.link_up).count() as f64 * sitl.ts_s
    );
    assert_eq!(sitl.watchdog_resets, WatchdogResets::default());
    assert!(s.iter().filter(|x| x.t_s > 9.5).all(|x| x.link_up));
    assert!(s.iter().filter(|x| x.t_s > 4.0).all(|x| x.altitude_m > 0.3));
}

/// The scenario's module settings are the module's own; the world binds an unbound module
/// to the flight side at `Scenario::rate` (before, the module's factory settings — bind ID 0
/// — waited for a bind and the link never came up).
#[test]
fn factory_module_settings_are_bound_at_the_scenario_rate() {
    let (quad, settings) = default_airframe();
    let sitl = run(Scenario {
        rate: RateMode::M100,
        module_settings: Some(module_core::settings::Settings::default()),
        ..Scenario::new(settings, quad, 1.0, Box::new(|_| PilotInput::default()))
    });
    assert!(sitl.samples.iter().all(|x| x.link_up));
    assert_eq!(
        sitl.settings.get(flight_app::settings::handles::LINK_RATE),
        1,
        "M100 stored on the flight side"
    );
}
