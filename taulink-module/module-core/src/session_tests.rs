use super::*;
use crate::settings::RateMode;

fn entropy() -> telemetry::link::Entropy {
    telemetry::link::Entropy::new([3; 32])
}

fn bound(role: Role) -> Settings {
    Settings {
        role,
        bind_id: 0x0BAD_F00D,
        link_key: Some(telemetry::link::LinkKey::from_bytes([0x0B; 16])),
        rate: RateMode::M100,
        band: Band::Mhz868,
        ..Settings::default()
    }
}

#[test]
fn a_missing_radio_is_probed_again_every_second() {
    let mut session = Session::new();
    let settings = bound(Role::Transmitter);
    assert_eq!(
        session.next(&settings, None, 0, 1, &mut entropy()),
        LinkStep::Probe
    );
    session.on_probe(false);
    assert_eq!(
        session.next(&settings, None, 10, 1, &mut entropy()),
        LinkStep::Wait { ms: 1_000 }
    );
    assert_eq!(
        session.next(&settings, None, 1_010, 1, &mut entropy()),
        LinkStep::Probe
    );
    session.on_probe(true);
    assert_eq!(
        session.next(&settings, None, 1_100, 1, &mut entropy()),
        LinkStep::RunMaster(link_params(&settings).unwrap())
    );
}

#[test]
fn a_running_loop_stops_on_a_bind_request_or_a_silent_hook() {
    let mut session = Session::new();
    let settings = bound(Role::Transmitter);
    session.on_probe(true);
    assert!(matches!(
        session.next(&settings, None, 5_000, 1, &mut entropy()),
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
    assert_eq!(
        session.next(&settings, None, 200, 1, &mut entropy()),
        LinkStep::Probe
    );
}

#[test]
fn a_master_bind_offers_a_fresh_id_and_reports_it() {
    let mut session = Session::new();
    let settings = Settings::default();
    session.on_probe(true);
    assert_eq!(
        session.next(&settings, None, 0, 1, &mut entropy()),
        LinkStep::WaitForBind
    );
    // Unbound, idle: only a bind request ends it; a silent hook does not (no loop runs).
    assert_eq!(session.poll(60_000, false), None);
    assert_eq!(session.poll(60_000, true), Some(SessionEnd::BindRequested));
    session.on_end(SessionEnd::BindRequested);
    let step = session.next(&settings, None, 60_050, 0xFEED_BEEF, &mut entropy());
    let expected = new_bind_params(&settings, 0xFEED_BEEF);
    let LinkStep::BindMaster {
        params,
        auth,
        key,
        timeout_us,
        ..
    } = step
    else {
        panic!("a master bind: {step:?}");
    };
    assert_eq!((params, timeout_us), (expected, BIND_TIMEOUT_US));
    assert_eq!(auth, telemetry::link::BindAuth::Anonymous, "no phrase set");
    assert_eq!(session.poll(90_000, true), None, "nothing stops a bind");
    let offer = session.on_bind_done().expect("an offer");
    assert_eq!(
        (offer.params, offer.bind_id, offer.model),
        (expected, expected.bind_id, None)
    );
    // A new module key; the link's key handed over is its key for the offered bind ID.
    let module_key = offer.module_key.expect("a key agreement");
    assert_eq!(key, module_key.for_link(expected.bind_id));
    assert_eq!(session.on_bind_done(), None, "reported once");
    assert_eq!(
        session.next(&settings, None, 90_000, 1, &mut entropy()),
        LinkStep::Probe
    );
}

#[test]
fn a_receiver_follows_with_every_channel_held_and_binds_on_its_band() {
    let mut session = Session::new();
    let settings = bound(Role::Receiver);
    session.on_probe(true);
    assert_eq!(
        session.next(&settings, None, 0, 1, &mut entropy()),
        LinkStep::RunFollower {
            params: link_params(&settings).unwrap(),
            failsafe: FailsafeValues([Failsafe::Hold; MAX_CHANNELS]),
            failsafe_us: DEFAULT_FAILSAFE_US,
        }
    );
    session.on_end(SessionEnd::BindRequested);
    let LinkStep::BindFollower {
        band,
        stored,
        allow_plain,
        timeout_us,
        ..
    } = session.next(&settings, None, 10, 1, &mut entropy())
    else {
        panic!("a follower bind");
    };
    assert_eq!(
        (band, stored, allow_plain, timeout_us),
        (Band::Mhz868, None, false, BIND_TIMEOUT_US)
    );
    assert_eq!(session.on_bind_done(), None);
}

#[test]
fn bind_results_map_to_outcomes() {
    use telemetry::link::follower::FollowerBind;
    use telemetry::link::master::MasterBind;
    assert_eq!(
        BindOutcome::offered::<()>(Ok(MasterBind::Mismatch)),
        BindOutcome::Offered(MasterBind::Mismatch)
    );
    assert_eq!(BindOutcome::offered(Err(())), BindOutcome::RadioFailed);
    assert_eq!(
        BindOutcome::listened::<()>(Ok(FollowerBind::NoOffer)),
        BindOutcome::Listened(FollowerBind::NoOffer)
    );
    assert_eq!(BindOutcome::listened(Err(())), BindOutcome::RadioFailed);
    assert_eq!(
        BindOutcome::openlrs::<()>(Ok(true)),
        BindOutcome::OpenLrs { accepted: true }
    );
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
        session.next(&settings, Some(3), 0, 1, &mut entropy()),
        LinkStep::RunMaster(base.for_model(3))
    );
    session.on_end(SessionEnd::BindRequested);
    let LinkStep::BindMaster { params, key, .. } =
        session.next(&settings, Some(5), 10, 0xFEED_BEEF, &mut entropy())
    else {
        panic!("a master bind");
    };
    assert_eq!(params, base.for_model(5));
    assert_eq!(
        session.on_bind_done(),
        Some(Offer {
            params: base.for_model(5),
            bind_id: settings.bind_id,
            module_key: settings.link_key,
            model: Some(5)
        }),
        "the module keeps its key under a model"
    );
    assert_eq!(
        key,
        settings
            .link_key
            .unwrap()
            .for_link(base.for_model(5).bind_id),
        "model 5's link has its own key"
    );
    // Unbound, a model's first bind draws a fresh ID and offers that ID's model link.
    let mut session = Session::new();
    let unbound = Settings::default();
    session.on_probe(true);
    session.next(&unbound, Some(2), 0, 1, &mut entropy());
    session.on_end(SessionEnd::BindRequested);
    let fresh = new_bind_params(&unbound, 0xFEED_BEEF);
    assert!(matches!(
        session.next(&unbound, Some(2), 10, 0xFEED_BEEF, &mut entropy()),
        LinkStep::BindMaster { params, .. } if params == fresh.for_model(2)
    ));
    assert_eq!(
        session.on_bind_done().map(|o| o.bind_id),
        Some(fresh.bind_id)
    );
}
