//! The link's stream: telemetry down to the module, a setting change up and echoed, and the
//! system-identification flight whose result is reported.

#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

mod common;

use common::*;
use flight_app::supervisor::Decision;
use flight_sitl::metrics::{window, worst};
use flight_sitl::scenario::default_airframe;
use flight_sitl::{PilotInput, Scenario, run};

#[test]
fn telemetry_reaches_the_module_and_settings_come_back() {
    use flight_app::report::f32_value;
    use flight_app::settings::{PARAMS, handles};
    use telemetry::messages::{FlightMode, Message, SettingChange};
    let (quad, settings) = default_airframe();
    let id = PARAMS
        .iter()
        .position(|p| p.name == "failsafe.descent_mps")
        .unwrap() as u16;
    let change = SettingChange {
        id,
        value: f32_value(0.9),
    };
    // A keyed pair: the phone signs its change with the link's change key (which a phone
    // that proved the phrase gets from the module).
    let key = telemetry::link::LinkKey::from_bytes(*b"module key, sitl");
    let sitl = run(Scenario {
        settings,
        quad,
        seed: 3,
        duration_s: 6.0,
        link_failsafe_ms: 500,
        pilot: Box::new(pilot(-1.0, |_| cruise(-1.0))),
        setting_changes: vec![change],
        packet_loss: 0.0,
        rate: telemetry::link::RateMode::F250,
        module_settings: Some(module_core::settings::Settings {
            link_key: Some(key),
            ..module_core::settings::Settings::default()
        }),
        flight_flash: flight_sitl::FlashInjection::Stored,
        gps: None,
    });
    let rx = &sitl.module_rx;
    let per_s = rx.len() as f64 / 5.5;
    println!("module received {} messages ({per_s:.0}/s)", rx.len());
    assert!(per_s > 30.0, "{per_s}");
    // The change was applied on the flight side and echoed.
    assert_eq!(sitl.settings.get(handles::FAILSAFE_DESCENT_MPS), 0.9);
    assert!(rx.iter().any(|(_, m)| *m == Message::SettingChange(change)));
    // Armed state after the gesture (armed at 1.507 s; allow the downlink's latency).
    let armed_at = rx
        .iter()
        .find(|(_, m)| matches!(m, Message::ArmState(a) if a.armed))
        .map(|(t, _)| *t)
        .unwrap();
    let armed = sitl
        .samples
        .iter()
        .find(|x| x.out.decision == Decision::Armed)
        .unwrap()
        .t_s;
    println!("armed at {armed:.3} s, the module saw it at {armed_at:.3} s");
    assert!(armed_at > armed && armed_at - armed < 0.05, "{armed_at}");
    assert!(
        rx.iter()
            .any(|(_, m)| *m == Message::FlightMode(FlightMode::Attitude))
    );
    // Attitude in hover (truth within 0.35°, estimate within 0.3° of it): within 1°.
    let hover: Vec<_> = rx
        .iter()
        .filter_map(|(t, m)| match m {
            Message::Attitude(a) if *t > 3.0 => Some(*a),
            _ => None,
        })
        .collect();
    assert!(hover.len() > 40, "{}", hover.len());
    assert!(
        hover
            .iter()
            .all(|a| a.roll_cdeg.abs() < 100 && a.pitch_cdeg.abs() < 100),
        "{hover:?}"
    );
    let link = rx
        .iter()
        .rev()
        .find_map(|(_, m)| match m {
            Message::LinkStats(l) => Some(*l),
            _ => None,
        })
        .unwrap();
    println!("flight-side link stats: {link:?}");
    assert!(link.uplink_lq >= 95, "{link:?}");
    assert!(link.downlink_lq >= 95, "{link:?}");
    let battery = rx
        .iter()
        .rev()
        .find_map(|(_, m)| match m {
            Message::Battery(b) => Some(*b),
            _ => None,
        })
        .unwrap();
    assert!((4_130..=4_170).contains(&battery.voltage_mv), "{battery:?}");
}

#[test]
fn system_identification_flight_finds_the_airframe() {
    use telemetry::messages::{Axis, Message};
    let mut settings = airframe_settings();
    settings.set_text("mode.switch_high", "sysid").unwrap();
    // Hover, then 30 s of shake (switch high), then back to attitude mode.
    let sitl = fly(
        settings,
        36.0,
        pilot(-1.0, |t| PilotInput {
            mode_switch: if (5.0..35.0).contains(&t) { 1.0 } else { -1.0 },
            ..cruise(-1.0)
        }),
    );
    let s = &sitl.samples;
    let done = s.iter().find(|x| x.identification.is_some()).unwrap();
    let id = done.identification.unwrap();
    println!("identified at {:.2} s: {id:?}", done.t_s);
    assert!((35.0..35.1).contains(&done.t_s), "{}", done.t_s);
    // quad-sim's truth: ln β 10 / 10 / 6.5, τ 30 ms; the per-axis model leaves out the rigid
    // body's cross-coupling (≈ −0.07 on yaw at this inertia ratio, tests/quad-sim).
    let [lr, lp, ly] = id.ln_beta;
    assert!(
        (lr - 10.0).abs() < 0.15 && (lp - 10.0).abs() < 0.15,
        "{id:?}"
    );
    assert!((ly - 6.5).abs() < 0.25, "{id:?}");
    assert!((id.tau_s - 0.03).abs() < 0.006, "{id:?}");
    // The frame stayed controlled while shaking.
    let shaking = window(s, 6.0, 35.0);
    let tilt = worst(&shaking, |x| {
        x.truth.euler_deg[0].abs().max(x.truth.euler_deg[1].abs())
    });
    println!("worst tilt while shaking {tilt:.1}°");
    assert!(tilt < 15.0, "{tilt}");
    // The three results reached the module.
    let results: Vec<_> = sitl
        .module_rx
        .iter()
        .filter_map(|(t, m)| match m {
            Message::SysIdResult(r) => Some((*t, *r)),
            _ => None,
        })
        .collect();
    assert_eq!(
        results.iter().map(|(_, r)| r.axis).collect::<Vec<_>>(),
        vec![Axis::Roll, Axis::Pitch, Axis::Yaw]
    );
    assert!(
        results
            .iter()
            .all(|(t, _)| *t > done.t_s && *t < done.t_s + 0.3)
    );
    let roll = results[0].1;
    assert!((roll.beta1.ln() - lr).abs() < 1e-3 && roll.tau_s == id.tau_s);
}

#[test]
fn the_home_reaches_the_module_with_the_complementary_filter_and_a_fix() {
    use telemetry::messages::Message;
    // GIVEN the factory estimator (the complementary filter: no INS) and a receiver
    let (quad, settings) = default_airframe();
    assert_eq!(
        settings.get(flight_app::settings::handles::INS_MODE),
        0,
        "factory: complementary"
    );
    let sitl = run(Scenario {
        gps: Some(flight_sitl::gps::GpsConfig::default()),
        ..Scenario::new(settings, quad, 6.0, Box::new(pilot(-1.0, |_| cruise(-1.0))))
    });
    // WHEN it flies for 6 s
    // THEN the module hears the home (the first usable fix: the simulated field near Zürich),
    // which is what the ground station's home marker shows
    let homes: Vec<_> = sitl
        .module_rx
        .iter()
        .filter_map(|(t, m)| match m {
            Message::Home(h) => Some((*t, *h)),
            _ => None,
        })
        .collect();
    let (_, home) = *homes.first().expect("a Home message");
    println!("{home:?}, {} Home messages", homes.len());
    assert!(home.set);
    // Within the receiver's 0.5 m of noise of the field's position (1e-7° ≈ 1.1 cm).
    assert!((home.latitude_e7 - 473_977_420).abs() < 100, "{home:?}");
    assert!((home.longitude_e7 - 85_455_940).abs() < 150, "{home:?}");
}
