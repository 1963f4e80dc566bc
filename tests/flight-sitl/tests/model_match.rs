//! Model match at chip level (spec §12.6): the module's application with CRSF input, the
//! radio sending its model ID (model-select command) as EdgeTX does, the flight
//! application bound under one model. The model it was bound under flies; another model
//! never gets channels to it (the flight side never hears that model's link); with model
//! match off, any model flies a receiver bound without it.

#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::cast_precision_loss
)]

mod common;

use common::*;
use flight_sitl::scenario::default_airframe;
use flight_sitl::{PilotInput, Scenario, Sitl, run};
use module_core::settings::{InputProtocol, OutputProtocol, Settings as ModuleSettings};

/// Arming gesture and take-off with the radio on `model(t)`; the module has model match
/// `on`, a receiver bound under the models of `bound` (the flight side under the lowest).
fn fly_model(on: bool, bound: u64, model: impl Fn(f64) -> u8 + 'static) -> Sitl {
    let (quad, settings) = default_airframe();
    let mut script = pilot(-1.0, |_| cruise(-1.0));
    run(Scenario {
        module_settings: Some(ModuleSettings {
            input: InputProtocol::Crsf,
            output: OutputProtocol::Crsf,
            model_match: on,
            bound_models: bound,
            ..ModuleSettings::default()
        }),
        ..Scenario::new(
            settings,
            quad,
            6.0,
            Box::new(move |t| PilotInput {
                radio_model: Some(model(t)),
                ..script(t)
            }),
        )
    })
}

fn link_up_share(sitl: &Sitl, from_s: f64, to_s: f64) -> f64 {
    let window: Vec<_> = sitl
        .samples
        .iter()
        .filter(|s| (from_s..to_s).contains(&s.t_s))
        .collect();
    window.iter().filter(|s| s.link_up).count() as f64 / window.len() as f64
}

fn armed(sitl: &Sitl) -> bool {
    sitl.samples.iter().any(|s| s.out.armed)
}

#[test]
fn the_model_it_was_bound_under_flies() {
    let sitl = fly_model(true, 1 << 3, |_| 3);
    let up = link_up_share(&sitl, 0.0, 6.0);
    println!("model 3 (bound): link up {:.1} % of loops", up * 100.0);
    assert!(up > 0.99, "{up}");
    assert!(armed(&sitl));
    assert!(sitl.samples.last().unwrap().altitude_m > 1.0);
    assert!(!sitl.module_rx.is_empty(), "telemetry comes back");
}

#[test]
fn another_model_never_gets_channels() {
    // Bound under model 3, the radio on model 5 from power-up.
    let sitl = fly_model(true, 1 << 3, |_| 5);
    assert_eq!(link_up_share(&sitl, -1.0, 6.0), 0.0);
    assert!(!armed(&sitl));
    assert!(
        sitl.module_rx.is_empty(),
        "nothing heard from the flight side"
    );
    // Switched from model 3 to model 5 on the ground: the link goes and stays down.
    let sitl = fly_model(true, 1 << 3, |t| if t < 0.3 { 3 } else { 5 });
    assert!(link_up_share(&sitl, 0.0, 0.2) > 0.99);
    let after = link_up_share(&sitl, 1.0, 6.0);
    println!(
        "switched to model 5 at 0.3 s: link up {:.1} % after 1 s",
        after * 100.0
    );
    assert_eq!(after, 0.0);
    assert!(!armed(&sitl));
}

#[test]
fn model_match_off_flies_any_model() {
    for model in [0, 5, 63] {
        let sitl = fly_model(false, 0, move |_| model);
        let up = link_up_share(&sitl, 0.0, 6.0);
        assert!(up > 0.99, "model {model}: {up}");
        assert!(armed(&sitl), "model {model}");
    }
}
