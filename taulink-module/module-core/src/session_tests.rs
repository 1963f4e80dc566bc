use super::*;
use crate::settings::RateMode;

fn bound(role: Role) -> Settings {
    Settings {
        role,
        bind_id: 0x0BAD_F00D,
        rate: RateMode::M100,
        band: Band::Mhz868,
        ..Settings::default()
    }
}

#[test]
fn a_missing_radio_is_probed_again_every_second() {
    let mut session = Session::new();
    let settings = bound(Role::Transmitter);
    assert_eq!(session.next(&settings, None, 0, 1), LinkStep::Probe);
    session.on_probe(false);
    assert_eq!(
        session.next(&settings, None, 10, 1),
        LinkStep::Wait { ms: 1_000 }
    );
    assert_eq!(session.next(&settings, None, 1_010, 1), LinkStep::Probe);
    session.on_probe(true);
    assert_eq!(
        session.next(&settings, None, 1_100, 1),
        LinkStep::RunMaster(link_params(&settings).unwrap())
    );
}

#[test]
fn a_running_loop_stops_on_a_bind_request_or_a_silent_hook() {
    let mut session = Session::new();
    let settings = bound(Role::Transmitter);
    session.on_probe(true);
    assert!(matches!(
        session.next(&settings, None, 5_000, 1),
        LinkStep::RunMaster(_)
    ));
    assert_eq!(session.poll(5_000 + HOOK_SILENCE_MS, false), None);
    assert_eq!(
        session.poll(5_001 + HOOK_SILENCE_MS, false),
        Some(SessionEnd::HookSilent)
    );
    session.on_hook(6_000);
    assert_eq!(session.poll(6_000 + HOOK_SILENCE_MS, false), None);
    // The clock wraps (u32 ms, 49.7 days): still measured as a difference.
    session.on_hook(u32::MAX - 10);
    assert_eq!(session.poll(100, false), None);
    assert_eq!(session.poll(100, true), Some(SessionEnd::BindRequested));
    session.on_end(SessionEnd::HookSilent);
    assert_eq!(session.next(&settings, None, 200, 1), LinkStep::Probe);
}

#[test]
fn a_master_bind_offers_a_fresh_id_and_reports_it() {
    let mut session = Session::new();
    let settings = Settings::default();
    session.on_probe(true);
    assert_eq!(session.next(&settings, None, 0, 1), LinkStep::WaitForBind);
    // Unbound, idle: only a bind request ends it; a silent hook does not (no loop runs).
    assert_eq!(session.poll(60_000, false), None);
    assert_eq!(session.poll(60_000, true), Some(SessionEnd::BindRequested));
    session.on_end(SessionEnd::BindRequested);
    let step = session.next(&settings, None, 60_050, 0xFEED_BEEF);
    let expected = new_bind_params(&settings, 0xFEED_BEEF);
    assert_eq!(
        step,
        LinkStep::BindMaster {
            params: expected,
            timeout_us: BIND_TIMEOUT_US
        }
    );
    assert_eq!(session.poll(90_000, true), None, "nothing stops a bind");
    assert_eq!(
        session.on_bind_done(),
        Some(Offer {
            params: expected,
            bind_id: expected.bind_id,
            model: None
        })
    );
    assert_eq!(session.on_bind_done(), None, "reported once");
    assert_eq!(session.next(&settings, None, 90_000, 1), LinkStep::Probe);
}

#[test]
fn a_receiver_follows_with_every_channel_held_and_binds_on_its_band() {
    let mut session = Session::new();
    let settings = bound(Role::Receiver);
    session.on_probe(true);
    assert_eq!(
        session.next(&settings, None, 0, 1),
        LinkStep::RunFollower {
            params: link_params(&settings).unwrap(),
            failsafe: FailsafeValues([Failsafe::Hold; MAX_CHANNELS]),
            failsafe_us: DEFAULT_FAILSAFE_US,
        }
    );
    session.on_end(SessionEnd::BindRequested);
    assert_eq!(
        session.next(&settings, None, 10, 1),
        LinkStep::BindFollower {
            band: Band::Mhz868,
            timeout_us: BIND_TIMEOUT_US
        }
    );
    assert_eq!(session.on_bind_done(), None);
}

#[test]
fn bind_results_map_to_outcomes() {
    assert_eq!(
        BindOutcome::offered::<()>(Ok(true)),
        BindOutcome::Offered { accepted: true }
    );
    assert_eq!(BindOutcome::offered(Err(())), BindOutcome::RadioFailed);
    assert_eq!(
        BindOutcome::listened::<()>(Ok(None)),
        BindOutcome::Listened(None)
    );
    assert_eq!(BindOutcome::listened(Err(())), BindOutcome::RadioFailed);
}

/// Model match: the running link and a bind offer carry the model's identity; a bound module
/// keeps its ID when it binds another model, so the receivers of the other models still fly.
#[test]
fn under_a_model_the_link_and_the_bind_use_the_models_identity() {
    let mut session = Session::new();
    let settings = bound(Role::Transmitter);
    let base = link_params(&settings).unwrap();
    session.on_probe(true);
    assert_eq!(
        session.next(&settings, Some(3), 0, 1),
        LinkStep::RunMaster(base.for_model(3))
    );
    session.on_end(SessionEnd::BindRequested);
    assert_eq!(
        session.next(&settings, Some(5), 10, 0xFEED_BEEF),
        LinkStep::BindMaster {
            params: base.for_model(5),
            timeout_us: BIND_TIMEOUT_US
        }
    );
    assert_eq!(
        session.on_bind_done(),
        Some(Offer {
            params: base.for_model(5),
            bind_id: settings.bind_id,
            model: Some(5)
        })
    );
    // Unbound, a model's first bind draws a fresh ID and offers that ID's model link.
    let mut session = Session::new();
    let unbound = Settings::default();
    session.on_probe(true);
    session.next(&unbound, Some(2), 0, 1);
    session.on_end(SessionEnd::BindRequested);
    let fresh = new_bind_params(&unbound, 0xFEED_BEEF);
    assert_eq!(
        session.next(&unbound, Some(2), 10, 0xFEED_BEEF),
        LinkStep::BindMaster {
            params: fresh.for_model(2),
            timeout_us: BIND_TIMEOUT_US
        }
    );
    assert_eq!(
        session.on_bind_done().map(|o| o.bind_id),
        Some(fresh.bind_id)
    );
}
