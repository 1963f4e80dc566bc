//! What blocking jobs cost the flight board (issue 12: time that costs): a gain design
//! (≈ 42 ms on the F405) holds its thread-mode executor — the supervisor does not feed the
//! IWDG meanwhile, but the flight loop, in its interrupt executor, flies on (issue 29); the
//! settings flash's writes and sector erases stall the whole CPU (code fetch from the
//! single-bank flash), the loop too.

#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss,
    clippy::cast_possible_truncation
)]

use flight_app::report::f32_value;
use flight_app::settings::{PARAMS, handles};
use flight_sitl::scenario::default_airframe;
use std::time::Duration;

use flight_sitl::{FlashInjection, PilotInput, Sample, Scenario, WARMUP_S, World};
use telemetry::link::LinkKey;
use telemetry::messages::SettingChange;

fn change(name: &str, value: f32) -> SettingChange {
    let id = PARAMS.iter().position(|p| p.name == name).unwrap() as u16;
    SettingChange {
        id,
        value: f32_value(value),
    }
}

/// The stretches (start, length) the flight board was held, s.
fn held(samples: &[Sample], ts_s: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut last = f64::NEG_INFINITY;
    for x in samples.iter().filter(|x| x.flight_busy) {
        match out.last_mut() {
            Some((_, len)) if x.t_s - last < 1.5 * ts_s => *len += ts_s,
            _ => out.push((x.t_s, ts_s)),
        }
        last = x.t_s;
    }
    out
}

/// On the ground, disarmed: the phone sends `changes` one by one from 1 s (one per
/// 20 ms), the world runs `seconds`.
fn on_the_ground(changes: &[SettingChange], seconds: f64) -> flight_sitl::Sitl {
    on_the_ground_with(changes, seconds, FlashInjection::Stored, true, false)
}

/// [`on_the_ground`] with the flash as `flash` holds it, the storage adapter stretching the
/// watchdog around saves or (`stretch` false) not, and the pilot typing `save` at the
/// console after the changes (`save`).
fn on_the_ground_with(
    changes: &[SettingChange],
    seconds: f64,
    flash: FlashInjection,
    stretch: bool,
    save: bool,
) -> flight_sitl::Sitl {
    let (quad, settings) = default_airframe();
    // A keyed pair: changes from the phone are signed with the link's change key (spec §12.5).
    let key = LinkKey::from_bytes(*b"costs of jobs...");
    let mut s = Scenario::new(
        settings,
        quad,
        seconds,
        Box::new(|_: f64| PilotInput::default()),
    );
    s.module_settings = Some(module_core::settings::Settings {
        link_key: Some(key),
        ..Default::default()
    });
    s.flight_flash = flash;
    let mut world = World::new(s);
    world.with_flight_lsi_hz(flight_app::app::LSI_MAX_HZ);
    if !stretch {
        world.without_save_watchdog_stretch();
    }
    world.run_for(Duration::from_secs_f64(WARMUP_S + 1.0));
    for c in changes {
        world.phone_change(*c);
        world.run_for(Duration::from_millis(20));
    }
    if save {
        // The pilot keeps the changes: a save, on the ground.
        world.run_for(Duration::from_millis(200));
        let replies = world.type_at_flight_console(b"save\r\n");
        assert_eq!(replies, ["saving\r\n"]);
    }
    world.run_to_end();
    world.finish()
}

#[test]
fn a_gain_design_holds_the_thread_tasks_but_not_the_loop() {
    // An LQG cost from the phone, on the ground: applied, the gains re-designed, saved.
    let sitl = on_the_ground(&[change("lqg.q_rate", 900.0)], 2.0);
    assert_eq!(sitl.settings.get(handles::LQG_Q_RATE), 900.0);
    let stretches = held(&sitl.samples, sitl.ts_s);
    println!("held: {stretches:?}");
    // The 42 ms design is no stretch of missed loops any more (it was, on one executor).
    assert!(
        stretches
            .iter()
            .all(|(_, len)| (*len - 0.042).abs() > 0.002),
        "a design stretch in {stretches:?}"
    );
    assert_eq!(sitl.watchdog_resets.flight, 0);
}

/// A save that needs a sector erase (the map ran out of room) holds the F405 for the erase
/// (250 ms typical, 500 ms max, DS8626) — beyond the IWDG's 200 ms on a chip whose LSI runs
/// at the datasheet's fastest 47 kHz. The storage adapter stretches the watchdog to the app's
/// `SaveJob::watchdog_ms` for it: no reset. Without the stretch the watchdog model sees the
/// stall and resets that flight controller.
#[test]
fn a_save_with_a_sector_erase_resets_nothing_because_the_watchdog_is_stretched() {
    let changes = [change("pid.roll.kp", 0.0042)];
    let sitl = on_the_ground_with(&changes, 2.0, FlashInjection::NearlyFull, true, true);
    let stretches = held(&sitl.samples, sitl.ts_s);
    println!("held: {stretches:?}");
    assert!(
        stretches.iter().any(|(_, len)| *len >= 0.25),
        "no sector-erase stretch in {stretches:?}"
    );
    assert_eq!(sitl.watchdog_resets.flight, 0);
    assert_eq!(
        sitl.settings
            .get(flight_app::settings::handles::PID_ROLL_KP),
        0.0042
    );

    let unstretched = on_the_ground_with(&changes, 2.0, FlashInjection::NearlyFull, false, true);
    assert!(
        unstretched.watchdog_resets.flight >= 1,
        "a 250 ms stall under a 200 ms watchdog must reset the flight controller"
    );
}
