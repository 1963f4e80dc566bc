use super::*;
use crate::outputs::Command;
use crate::pipeline::ImuSample;
use crate::supervisor::Sticks;
use telemetry::channels::ChannelFormat;
use telemetry::channels::FailsafeValues;
use telemetry::link::core::Follower;
use telemetry::link::follower::FollowerBind;
use telemetry::link::{Band, LinkParams, RateMode};

/// A level frame at rest; a tiny sample-dependent gyro wiggle like real sensor noise
/// (bit-identical samples are the frozen-data fault).
pub(super) fn resting(i: u32) -> ImuSample {
    let wiggle = (i % 13) as f32 * 1e-4;
    ImuSample {
        gyro_radps: [wiggle, -wiggle, 0.0],
        accel_mps2: [0.0, 0.0, -crate::estimation::GRAVITY_MPS2],
        mag: None,
    }
}

fn sticks(throttle: f32, yaw: f32) -> LinkInput {
    LinkInput {
        up: true,
        sticks: Sticks {
            throttle,
            yaw,
            ..Sticks::default()
        },
        arm_switch: None,
        mode_channel: -1.0,
    }
}

pub(super) fn some_link() -> LinkParams {
    LinkParams::new(
        0x5EC0_0001,
        Band::Mhz868,
        RateMode::F500,
        ChannelFormat::Full16,
        4,
    )
}

fn app() -> FlightApp {
    let Some(app) = FlightApp::new(Settings::default(), 0) else {
        panic!("factory settings make a setup");
    };
    app
}

/// Feeds `n` good samples at 1 ms from `t0`; returns the next time and the last step.
fn fly(app: &mut FlightApp, t0: u32, n: u32, link: LinkInput) -> (u32, ImuStep) {
    app.link_input = link;
    let mut last = None;
    for i in 0..n {
        last = Some(app.on_imu_sample(t0 + i, &resting(t0 + i)));
    }
    let Some(last) = last else {
        panic!("n > 0");
    };
    (t0 + n, last)
}

/// Arms with the yaw gesture and brings the throttle up to hover; returns the time.
pub(super) fn armed_in_the_air(app: &mut FlightApp) -> u32 {
    let (t, _) = fly(app, 0, 1500, sticks(0.0, 1.0));
    let (t, _) = fly(app, t, 100, sticks(0.0, 0.0));
    assert!(app.armed());
    let (t, step) = fly(app, t, 200, sticks(0.5, 0.0));
    assert!(
        step.motors
            .iter()
            .all(|m| matches!(m, Command::Throttle(x) if *x > 0.3))
    );
    t
}

fn running(step: &ImuStep) -> bool {
    step.motors
        .iter()
        .all(|m| matches!(m, Command::Throttle(_)))
}

#[test]
fn a_short_imu_stall_holds_the_last_command_then_disarms_with_a_reason() {
    let mut app = app();
    let t = armed_in_the_air(&mut app);
    let (_, before) = fly(&mut app, t - 1, 1, sticks(0.5, 0.0));
    // Data-ready missing, polled every 5 ms: the last command is held within the bound.
    let mut now = t;
    while now < t + STALL_RIDE_THROUGH_MS - 1 {
        let step = app.on_imu_missing(now, ImuFault::Stalled);
        assert_eq!(step.motors, before.motors, "held at {} ms", now - t);
        assert!(!step.reprobe);
        assert!(app.armed());
        now += 5;
    }
    let step = app.on_imu_missing(t + STALL_RIDE_THROUGH_MS, ImuFault::Stalled);
    assert_eq!(step.motors, [Command::Stopped; 4]);
    assert!(step.reprobe, "the adapter re-probes the sensor");
    assert!(!app.armed(), "disarmed, not 'armed with stopped motors'");
    assert_eq!(app.imu_fault(), Some(ImuFault::Stalled));
    let out = app.last_output().copied();
    assert_eq!(out.map(|o| o.decision), Some(Decision::DisarmedSensorFault));
    assert_ne!(
        app.arming_blockers() & blocker_bit(ArmBlocker::SensorsUnhealthy),
        0
    );
    // The distinct tone: the sensor-fault siren starts at 3.5 kHz.
    assert_eq!(app.on_alert_tick(t + STALL_RIDE_THROUGH_MS), 3500);
    let mut status = heapless::String::<512>::new();
    let _ = app.on_console_line("status", &mut status);
    assert!(status.contains("IMU fault: stalled"), "{status}");
    // Re-probed at most every 500 ms.
    assert!(!app.on_imu_missing(t + 100, ImuFault::Stalled).reprobe);
    assert!(
        app.on_imu_missing(
            t + STALL_RIDE_THROUGH_MS + REPROBE_PERIOD_MS,
            ImuFault::Stalled
        )
        .reprobe
    );
}

#[test]
fn motors_never_restart_after_an_imu_fault_without_a_fresh_arm() {
    let mut app = app();
    let t = armed_in_the_air(&mut app);
    let mut now = t;
    while now <= t + STALL_RIDE_THROUGH_MS {
        app.on_imu_missing(now, ImuFault::ReadError);
        now += 1;
    }
    assert_eq!(app.imu_fault(), Some(ImuFault::ReadError));
    // The sensor comes back; the pilot still holds hover throttle.
    let (now, step) = fly(&mut app, now, 2_000, sticks(0.5, 0.0));
    assert!(!running(&step));
    assert!(!app.armed());
    assert_eq!(app.imu_fault(), None, "good data clears the fault");
    // Only a new arm gesture (throttle low) starts them again.
    let (now, _) = fly(&mut app, now, 1_500, sticks(0.0, 1.0));
    let (_, step) = fly(&mut app, now, 100, sticks(0.0, 0.0));
    assert!(app.armed());
    assert!(running(&step));
}

#[test]
fn frozen_and_all_zero_samples_are_faults() {
    for bad in [
        resting(7),
        ImuSample {
            gyro_radps: [0.0; 3],
            accel_mps2: [0.0; 3],
            mag: None,
        },
    ] {
        let mut app = app();
        let t = armed_in_the_air(&mut app);
        let mut disarmed_at = None;
        for i in 0..200 {
            let step = app.on_imu_sample(t + i, &bad);
            if !app.armed() && disarmed_at.is_none() {
                disarmed_at = Some(i);
                assert_eq!(step.motors, [Command::Stopped; 4]);
            }
        }
        let Some(at) = disarmed_at else {
            panic!("{bad:?} never disarmed");
        };
        // Frozen data is usable for FROZEN_SAMPLES − 1 samples; then the ride-through runs.
        assert!(at <= FROZEN_SAMPLES as u32 + STALL_RIDE_THROUGH_MS, "{at}");
        // The last good sample came 1 ms before the first bad one.
        assert!(at + 1 >= STALL_RIDE_THROUGH_MS, "{at}");
        assert!(app.imu_fault().is_some());
    }
}

#[test]
fn a_still_noisy_sensor_is_never_a_fault() {
    let mut app = app();
    let (_, step) = fly(&mut app, 0, 5_000, sticks(0.0, 0.0));
    assert!(!step.reprobe);
    assert_eq!(app.imu_fault(), None);
    assert_eq!(app.arming_blockers(), 0);
}

/// Polls out the watchdog's start-up grace (every task alive for the first window).
fn starve(w: &mut Watchdog) {
    for _ in 0..CHECK_IN_POLLS {
        w.poll(0);
    }
}

/// The same through the app.
fn starve_app(app: &mut FlightApp) {
    for _ in 0..CHECK_IN_POLLS {
        app.on_watchdog_poll(0);
    }
}

#[test]
fn the_watchdog_is_fed_only_when_every_task_checked_in() {
    let mut w = Watchdog::new(0);
    // Every task starts alive for the window; with none checking in the feeds stop after it.
    for k in 1..=CHECK_IN_POLLS as u32 {
        assert!(w.poll(0), "grace poll {k}");
    }
    assert!(!w.poll(0));
    let mut w = Watchdog::new(0);
    starve(&mut w);
    for t in Task::ALL.iter().skip(1) {
        w.check_in(*t);
    }
    assert!(!w.poll(50));
    assert_eq!(
        w.missing().collect::<heapless::Vec<_, 8>>(),
        [Task::Heartbeat]
    );
    assert!(!w.expired(WATCHDOG_TIMEOUT_MS - 1));
    assert!(
        w.expired(WATCHDOG_TIMEOUT_MS),
        "no feed for the timeout is a reset"
    );
    w.check_in(Task::Heartbeat);
    assert!(w.poll(100));
    assert!(!w.expired(99 + WATCHDOG_TIMEOUT_MS));
}

#[test]
fn every_link_hook_call_checks_the_link_in() {
    let mut app = app();
    starve_app(&mut app);
    let mut follower = Follower::new(some_link(), FailsafeValues::default(), FAILSAFE_US);
    for t in Task::ALL {
        if t != Task::Link {
            app.check_in(t);
        }
    }
    assert!(!app.on_watchdog_poll(100));
    app.on_link_step(100_000, &mut follower);
    assert!(app.on_watchdog_poll(150));
    // Waiting outside the follower counts too (on a fresh app: the check-ins above stay
    // alive for CHECK_IN_POLLS polls).
    let mut app = self::app();
    starve_app(&mut app);
    for t in Task::ALL {
        if t != Task::Link {
            app.check_in(t);
        }
    }
    assert!(!app.on_watchdog_poll(100));
    app.on_link_idle();
    assert!(app.on_watchdog_poll(150));
    // Failsafe from the start: the loop sees the link down, and a link that never came up
    // is not a failsafe event in telemetry.
    assert!(!app.link_input().up);
    assert_eq!(app.link_failsafes(), 0);
}

#[test]
fn console_changes_are_refused_while_armed_and_request_designs_and_saves_when_not() {
    let mut app = app();
    let mut out = heapless::String::<256>::new();
    let _ = app.on_console_line("set battery.cells 3", &mut out);
    assert!(!out.contains("refused"), "{out}");
    let Some(request) = app.take_design_request() else {
        panic!("a change asks for a gain design");
    };
    assert_eq!(request, *app.settings());
    assert_eq!(app.take_design_request(), None, "once per change");
    assert_eq!(app.take_save(), None, "set alone does not save");
    let _ = app.on_console_line("save", &mut out);
    let Some((live, _stored)) = app.take_save() else {
        panic!("save requested");
    };
    app.on_saved(live);
    armed_in_the_air(&mut app);
    out.clear();
    let _ = app.on_console_line("defaults", &mut out);
    assert!(out.contains("refused"), "{out}");
    let _ = app.on_console_line("save", &mut out);
    assert_eq!(app.take_save(), None);
}

/// A boot-time settings problem (issue 13): status says it, telemetry carries it as a
/// standing arming blocker, the arm gesture is refused; a save fixes it.
#[test]
fn a_settings_problem_at_boot_refuses_arming_until_a_save() {
    let mut app = app();
    app.on_settings_problem(LoadProblem::Corrupt);
    let bit = blocker_bit(ArmBlocker::SettingsProblem);
    assert_eq!(
        app.arming_blockers() & bit,
        bit,
        "standing, before any arm try"
    );
    let mut status = heapless::String::<512>::new();
    let _ = app.on_console_line("status", &mut status);
    assert!(status.contains("settings problem"), "{status}");
    let (t, _) = fly(&mut app, 0, 1500, sticks(0.0, 1.0));
    let (t, _) = fly(&mut app, t, 100, sticks(0.0, 0.0));
    assert!(!app.armed(), "a corrupt store flies nothing");
    // The pilot: `defaults`, `save`. The whole set is written though nothing changed.
    let mut out = heapless::String::<256>::new();
    let _ = app.on_console_line("defaults", &mut out);
    let _ = app.on_console_line("save", &mut out);
    assert!(app.save_whole());
    let Some((live, _)) = app.take_save() else {
        panic!("a save is due");
    };
    app.on_saved(live);
    assert_eq!(app.arming_blockers() & bit, 0);
    assert_eq!(app.settings_problem(), None);
    let (t, _) = fly(&mut app, t, 1500, sticks(0.0, 1.0));
    let _ = fly(&mut app, t, 100, sticks(0.0, 0.0));
    assert!(app.armed(), "arms once the settings are saved");
}

/// A bind result with a key (the links the tests bind are authenticated).
pub(super) fn bound(params: LinkParams) -> FollowerBind {
    FollowerBind::Bound {
        params,
        key: Some(telemetry::link::LinkKey::from_bytes([0x6B; 16])),
    }
}

#[test]
fn an_unbound_controller_runs_no_link_and_nothing_binds_it_without_the_bind_command() {
    let mut app = app();
    assert_eq!(app.link_params(), None, "no shared default link");
    assert_eq!(app.take_bind_request(), None, "no bind window at boot");
    // A bind offer heard without a window opened by the owner (the old 3 s boot window)
    // is not stored.
    assert!(!app.on_bind_result(&bound(some_link())));
    assert_eq!(app.link_params(), None);
    assert_eq!(app.take_save(), None);
}

#[test]
fn the_bind_command_opens_one_window_and_only_its_bind_is_stored() {
    let mut app = app();
    let mut out = heapless::String::<256>::new();
    let _ = app.on_console_line("bind", &mut out);
    assert!(out.contains("bind window open for 30 s"), "{out}");
    assert!(app.bind_requested());
    let request = app.take_bind_request().expect("a window");
    assert_eq!(
        (
            request.band,
            request.window_us,
            request.phrase,
            request.allow_plain
        ),
        (Band::Mhz433, BIND_WINDOW_US, None, false)
    );
    assert!(!app.bind_requested());
    assert_eq!(app.take_bind_request(), None, "one window per command");
    assert!(app.on_bind_result(&bound(some_link())));
    assert_eq!(app.link_params(), Some(some_link()));
    assert!(app.take_save().is_some(), "the bind is saved");
    // The window is closed: a second offer (a spoofer's) does not rebind.
    let other = LinkParams::new(
        0xBAD0_0BAD,
        Band::Mhz433,
        RateMode::L50,
        ChannelFormat::Compact8,
        2,
    );
    assert!(!app.on_bind_result(&bound(other)));
    assert_eq!(app.link_params(), Some(some_link()), "stays bound");
    // A window that times out closes too.
    let _ = app.on_console_line("bind", &mut out);
    assert!(app.take_bind_request().is_some());
    assert!(!app.on_bind_result(&FollowerBind::NoOffer));
    assert!(!app.on_bind_result(&bound(other)));
    assert_eq!(app.link_params(), Some(some_link()));
}

#[test]
fn bind_is_refused_while_armed() {
    let mut app = app();
    armed_in_the_air(&mut app);
    let mut out = heapless::String::<256>::new();
    let _ = app.on_console_line("bind", &mut out);
    assert!(out.contains("refused"), "{out}");
    assert!(!app.bind_requested());
    assert_eq!(app.take_bind_request(), None);
    assert!(!app.on_bind_result(&bound(some_link())));
    assert_eq!(app.link_params(), None);
}

#[test]
fn bind_is_refused_when_the_rng_failed_at_boot() {
    let mut app = app();
    app.on_boot_facts(crate::app::BootFacts {
        rng_fallback: true,
        ..Default::default()
    });
    let mut out = heapless::String::<256>::new();
    let _ = app.on_console_line("bind amber kettle under the oak", &mut out);
    assert!(out.contains("refused: the RNG failed"), "{out}");
    assert!(!app.bind_requested());
    assert_eq!(app.take_bind_request(), None);
}

#[test]
fn a_setting_change_over_the_link_is_refused_while_armed() {
    use crate::report::f32_value;
    use crate::settings::{PARAMS, handles};
    use telemetry::messages::{Message, SettingChange, encode_message};
    let mut app = app();
    let Some(id) = PARAMS.iter().position(|p| p.name == "failsafe.descent_mps") else {
        panic!("parameter exists");
    };
    let before = app.settings().get(handles::FAILSAFE_DESCENT_MPS);
    let change = SettingChange {
        id: id as u16,
        value: f32_value(before + 0.5),
    };
    let mut bytes = [0u8; 64];
    let n = encode_message(&Message::SettingChange(change), &mut bytes)
        .unwrap()
        .len();
    let mut follower = Follower::new(some_link(), FailsafeValues::default(), FAILSAFE_US);
    armed_in_the_air(&mut app);
    follower.uplink_stream.on_data(0, &bytes[..n]);
    app.on_link_step(100_000, &mut follower);
    assert!(app.armed());
    assert_eq!(app.settings().get(handles::FAILSAFE_DESCENT_MPS), before);
    assert_eq!(app.take_design_request(), None);
}

/// The link task's decision lives in the app: nothing while unbound, a bind window once the
/// console asks (and only once), the stored link after a bind.
#[test]
fn the_link_task_is_told_what_to_do_next() {
    let mut app = app();
    assert_eq!(app.next_link_step(), LinkStep::WaitForBind);
    let mut out = heapless::String::<256>::new();
    let _ = app.on_console_line("bind", &mut out);
    let LinkStep::Bind(request) = app.next_link_step() else {
        panic!("a bind window");
    };
    assert_eq!(
        (request.band, request.window_us),
        (Band::Mhz433, BIND_WINDOW_US)
    );
    assert!(app.on_bind_result(&bound(some_link())));
    assert_eq!(app.next_link_step(), LinkStep::Follow(some_link()));
}

/// The telemetry the link carries: altitude above the power-up point (the MS5611 reads
/// standard-atmosphere altitude, here 350 m) and the estimator's vertical speed, and the
/// battery monitor's cell count.
#[test]
fn telemetry_carries_altitude_from_the_power_up_point_vario_and_cells() {
    use telemetry::messages::{Decoded, Message, MessageReader};
    let mut app = app();
    let mut follower = Follower::new(some_link(), FailsafeValues::default(), FAILSAFE_US);
    let mut reader = MessageReader::new();
    let mut got = Vec::new();
    let mut chunk = [0u8; 64];
    // 1 s on the ground at 350 m, then a 1 m/s climb for 2 s, then 4 s held at 352 m.
    let baro = |t: u32| match t {
        0..1_000 => 350.0,
        1_000..3_000 => 350.0 + (t - 1_000) as f32 / 1_000.0,
        _ => 352.0,
    };
    for t in 0..7_000u32 {
        app.on_imu_sample(t, &resting(t));
        if t % 20 == 0 {
            app.on_baro(t, Some(baro(t)));
            // A 1S pack at ≈ 4.0 V through the default 1:2 divider.
            app.on_battery(t, 2_500, None);
        }
        if t % 4 == 0 {
            app.on_link_step(u64::from(t) * 1_000, &mut follower);
            let (_, n) = follower.downlink_stream.fill(&mut chunk);
            let ack = follower.downlink_stream.acked_total() as u8;
            follower.downlink_stream.on_ack(ack.wrapping_add(n as u8));
            for b in &chunk[..n] {
                if let Some(Decoded::Message(m)) = reader.push(*b) {
                    got.push((t, m));
                }
            }
        }
    }
    let vertical: Vec<(u32, telemetry::messages::Vertical)> = got
        .iter()
        .filter_map(|(t, m)| match m {
            Message::Vertical(v) => Some((*t, *v)),
            _ => None,
        })
        .collect();
    assert!(vertical.len() > 20, "{}", vertical.len());
    // Counted from the power-up point, not from the standard atmosphere's sea level.
    let (_, first) = vertical[0];
    assert!(first.altitude_cm.abs() < 20, "{first:?}");
    // The resting accelerometer never sees this climb start, so the blended estimate
    // follows the baro rate with its 1 s time constant: most of 1 m/s by the climb's end.
    let climbing: Vec<_> = vertical
        .iter()
        .filter(|(t, _)| (2_500..3_000).contains(t))
        .collect();
    assert!(!climbing.is_empty());
    assert!(
        climbing
            .iter()
            .all(|(_, v)| (60..=110).contains(&v.vario_cm_s)),
        "{climbing:?}"
    );
    let (_, last) = vertical[vertical.len() - 1];
    assert!((190..=210).contains(&last.altitude_cm), "{last:?}");
    assert!(last.vario_cm_s.abs() <= 10, "{last:?}");
    let cells = app.battery().map(|b| b.cells).unwrap_or(0);
    assert!(cells > 0);
    assert!(
        got.iter()
            .any(|(_, m)| *m == Message::Cells(telemetry::messages::Cells { count: cells }))
    );
}

mod gps {
    use telemetry::messages::GpsFix;
    use ubx::{FixType, Generation, NavPvt, Status, frame};

    use super::*;

    fn pvt(itow_ms: u32) -> NavPvt {
        NavPvt {
            itow_ms,
            fix_type: FixType::Fix3D,
            flags: NavPvt::FLAG_GNSS_FIX_OK,
            num_sv: 11,
            lon_e7: 80_123_456,
            lat_e7: 470_654_321,
            height_mm: 550_000,
            h_msl_mm: 500_000,
            h_acc_mm: 900,
            v_acc_mm: 1_400,
            vel_ned_mmps: [100, -200, 0],
            g_speed_mmps: 224,
            head_mot_e5: -6_343_000,
            s_acc_mmps: 150,
            p_dop_e2: 130,
        }
    }

    fn bytes(p: &NavPvt) -> Vec<u8> {
        frame::encode(0x01, 0x07, &p.encode()).unwrap().to_vec()
    }

    #[test]
    fn nav_pvt_bytes_reach_the_estimator_and_telemetry_once_a_second() {
        let mut a = app();
        // Chopped into odd pieces, as UART reads come.
        let b = bytes(&pvt(1_000));
        for chunk in b.chunks(7) {
            a.on_gps_bytes(10, chunk);
        }
        let (latest, _) = a.gps_latest().unwrap();
        assert_eq!(latest, pvt(1_000));
        let Some(telemetry::messages::Message::Gps(g)) = a.take_gps_report() else {
            panic!("a Gps message is due");
        };
        assert_eq!(g.fix, GpsFix::Fix3d);
        assert_eq!((g.latitude_e7, g.longitude_e7), (470_654_321, 80_123_456));
        assert_eq!(g.altitude_cm, 50_000);
        assert_eq!(g.ground_speed_cm_s, 22);
        // headMot −63.43° → 296.57°
        assert_eq!(g.course_cdeg, 29_657);
        assert_eq!(g.satellites, 11);
        // The next fix 200 ms later is not reported; one a second later is.
        a.on_gps_bytes(210, &bytes(&pvt(1_200)));
        assert_eq!(a.take_gps_report(), None);
        a.on_gps_bytes(1_010, &bytes(&pvt(2_000)));
        assert!(a.take_gps_report().is_some());
        assert_eq!(a.gps_latest().unwrap().0.itow_ms, 2_000);
    }

    #[test]
    fn the_home_goes_to_telemetry_once_set_then_every_five_seconds() {
        // The home is the full INS's (`ins.mode ins`), once it runs.
        let mut settings = Settings::default();
        settings.set_text("ins.mode", "ins").unwrap();
        let mut a = FlightApp::new(settings, 0).unwrap();
        fly(&mut a, 0, 3_000, sticks(0.0, 0.0));
        assert_eq!(a.take_home_report(), None, "no fix, no home");
        a.on_gps_bytes(3_000, &bytes(&pvt(1_000)));
        // The loop fuses it with its next step.
        fly(&mut a, 3_000, 1, sticks(0.0, 0.0));
        let home = a
            .view
            .as_ref()
            .unwrap()
            .estimator
            .home
            .expect("the first fix is home");
        // The link's report queue sends it (after the state change out of turn).
        let mut reader = telemetry::messages::MessageReader::new();
        let mut sent = Vec::new();
        for _ in 0..3 {
            let mut buf = [0u8; telemetry::messages::FRAMED_MAX_BYTES];
            let n = a
                .next_report(crate::report::LinkSeen::default(), &mut buf)
                .unwrap()
                .len();
            sent.extend(buf[..n].iter().filter_map(|&b| reader.push(b)));
        }
        let Some(telemetry::messages::Decoded::Message(telemetry::messages::Message::Home(h))) =
            sent.into_iter().find(|d| {
                matches!(
                    d,
                    telemetry::messages::Decoded::Message(telemetry::messages::Message::Home(_))
                )
            })
        else {
            panic!("a Home message is sent once the home is set");
        };
        assert_eq!(
            h,
            telemetry::messages::Home {
                latitude_e7: 470_654_321,
                longitude_e7: 80_123_456,
                altitude_cm: 50_000,
                set: true,
            }
        );
        assert_eq!((home.lat_e7, home.lon_e7), (h.latitude_e7, h.longitude_e7));
        // Not repeated before the period; repeated after it (each fix fused by the loop's
        // next step).
        a.on_gps_bytes(4_000, &bytes(&pvt(2_000)));
        fly(&mut a, 4_000, 1, sticks(0.0, 0.0));
        assert_eq!(a.take_home_report(), None);
        let t = 3_000 + HOME_REPORT_PERIOD_MS;
        a.on_gps_bytes(t, &bytes(&pvt(6_000)));
        fly(&mut a, t, 1, sticks(0.0, 0.0));
        assert_eq!(
            a.take_home_report(),
            Some(telemetry::messages::Message::Home(h))
        );
        // A home that moves goes out at once, period or not.
        let moved = crate::estimation::ins::aiding::gps::Home {
            lat_e7: home.lat_e7 + 100,
            ..home
        };
        a.gps.on_home(t + 10, Some(moved));
        let Some(telemetry::messages::Message::Home(m)) = a.take_home_report() else {
            panic!("a moved home is reported at once");
        };
        assert_eq!(m.latitude_e7, 470_654_421);
    }

    #[test]
    fn the_home_goes_to_telemetry_with_the_complementary_filter_too() {
        // GIVEN the factory estimator (`ins.mode complementary`: no INS at all) and then the
        // indoor INS, each with a receiver
        for mode in ["complementary", "ins_indoor"] {
            let mut settings = Settings::default();
            settings.set_text("ins.mode", mode).unwrap();
            let mut a = FlightApp::new(settings, 0).unwrap();
            fly(&mut a, 0, 3_000, sticks(0.0, 0.0));
            // WHEN a usable fix arrives
            a.on_gps_bytes(3_000, &bytes(&pvt(1_000)));
            // (the loop fuses it with its next step)
            fly(&mut a, 3_000, 1, sticks(0.0, 0.0));
            // THEN it is home, and the Home message is due
            let estimator = a.view.as_ref().unwrap().estimator;
            let home = estimator.home.expect("the first fix is home");
            assert_eq!(
                (home.lat_e7, home.lon_e7),
                (470_654_321, 80_123_456),
                "{mode}"
            );
            assert_eq!(
                a.take_home_report(),
                Some(telemetry::messages::Message::Home(
                    telemetry::messages::Home {
                        latitude_e7: 470_654_321,
                        longitude_e7: 80_123_456,
                        altitude_cm: 50_000,
                        set: true,
                    }
                )),
                "{mode}"
            );
            assert!(estimator.gps_fix, "{mode}");
            assert_eq!(estimator.source, {
                if mode == "complementary" {
                    crate::pipeline::Source::Complementary
                } else {
                    crate::pipeline::Source::Ins
                }
            });
        }
    }

    #[test]
    fn the_receiver_is_configured_as_m9_and_as_m8_after_a_nak() {
        let mut a = app();
        let first = a.gps_to_send(0).unwrap().to_vec();
        assert_eq!(&first[2..4], &[0x06, 0x8A], "CFG-VALSET first");
        assert_eq!(a.gps_to_send(10), None, "waits for the answer");
        // NAK of CFG-VALSET: a u-blox 8.
        a.on_gps_bytes(50, &frame::encode(0x05, 0x00, &[0x06, 0x8A]).unwrap());
        let next = a.gps_to_send(60).unwrap().to_vec();
        assert_eq!(&next[2..4], &[0x06, 0x00], "CFG-PRT of the M8 sequence");
        assert_eq!(
            a.gps_config_status(),
            (Generation::M8, Status::Pending { step: 0 })
        );
        let bauds = gps_baud_messages();
        assert_eq!(&bauds[0][2..4], &[0x06, 0x8A]);
        assert_eq!(&bauds[1][2..4], &[0x06, 0x00]);
    }
}

/// Dynamic power (`link.dynamic_power`): with no report from the master (not on its grid
/// yet) the follower is asked for the maximum, step 7, and so with the setting off; the
/// walk in `tests/taulink-sim` (`--dynamic-power --walk`) shows the step following the link.
#[test]
fn the_link_hook_asks_the_follower_for_its_power_step() {
    use crate::settings::handles;
    let mut app = app();
    assert_eq!(
        app.settings().get(handles::LINK_DYNAMIC_POWER),
        1,
        "factory: on"
    );
    let mut follower = Follower::new(some_link(), FailsafeValues::default(), FAILSAFE_US);
    assert_eq!(follower.tx_power(), None);
    app.on_link_step(100_000, &mut follower);
    assert_eq!((follower.tx_power(), app.tx_power_step()), (Some(7), 7));
    let mut settings = app.settings().clone();
    settings
        .apply(&[handles::LINK_DYNAMIC_POWER.to(0)])
        .unwrap();
    let mut fixed = FlightApp::new(settings, 0).unwrap();
    let mut follower = Follower::new(some_link(), FailsafeValues::default(), FAILSAFE_US);
    fixed.on_link_step(100_000, &mut follower);
    assert_eq!(follower.tx_power(), Some(7));
}
