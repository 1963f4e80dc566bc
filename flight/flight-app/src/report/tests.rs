use super::*;
use crate::battery::BatteryLevel;
use crate::outputs::Command;
use crate::settings::handles;
use crate::supervisor::{Decision, FlightMode};
use telemetry::messages::{Decoded, MessageReader, encode_message};

fn snapshot() -> Snapshot {
    Snapshot {
        out: LoopOutput {
            motors: [Command::Stopped; 4],
            decision: Decision::Steady,
            mode: FlightMode::RateLqg,
            mode_changed: false,
            armed: true,
            failsafe: false,
            attitude: crate::pipeline::Attitude::from_deg([12.345, -200.0, 123.455]),
            estimator: crate::pipeline::Source::Complementary,
        },
        battery: Some(BatteryStatus {
            voltage_mv: 3_987,
            current_ma: 2_345,
            consumed_mah: 120,
            cells: 1,
            level: BatteryLevel::Ok,
            level_changed: false,
        }),
        link: LinkSeen {
            rssi_dbm: -71,
            lq_percent: 97,
            downlink: Some((-80, 90)),
            rate_mode: 2,
            received: 1000,
            missed: 30,
            failsafes: 1,
        },
        arming_blockers: 0,
        sysid: None,
        altitude_m: Some(12.345),
        climb_mps: Some(-0.5),
    }
}

#[test]
fn rotation_carries_every_kind_and_attitude_half_the_time() {
    let snap = snapshot();
    let mut r = Reporter::new();
    let msgs: Vec<Message> = (0..ROTATION.len()).map(|_| r.next(&snap)).collect();
    let attitude = Message::Attitude(Attitude {
        roll_cdeg: 1234,
        pitch_cdeg: -18_000,
        yaw_cdeg: 12_345,
    });
    assert_eq!(msgs.iter().filter(|m| **m == attitude).count(), 7);
    assert!(msgs.contains(&Message::ArmState(ArmState {
        armed: true,
        failsafe: false,
        arming_blockers: 0
    })));
    assert!(msgs.contains(&Message::Battery(Battery {
        voltage_mv: 3_987,
        current_ca: 234,
        used_mah: 120,
        remaining_percent: 0
    })));
    // The LQG rate mode is reported as itself (once both rate modes were "Rate").
    assert!(msgs.contains(&Message::FlightMode(FlightMode::RateLqg)));
    assert!(msgs.iter().any(|m| matches!(
        m,
        Message::LinkStats(LinkStats {
            uplink_rssi_dbm: -71,
            uplink_lq: 97,
            downlink_lq: 90,
            ..
        })
    )));
    // Without a battery reading the slot goes to the next kind.
    let mut snap = snapshot();
    snap.battery = None;
    let mut r = Reporter::new();
    assert!(
        (0..16)
            .map(|_| r.next(&snap))
            .all(|m| !matches!(m, Message::Battery(_)))
    );
    // A sysid result jumps the queue.
    snap.sysid = Some(sysid_message(Axis::Roll, 22_000.0, 0.0, 0.03, 1.5));
    assert!(matches!(r.next(&snap), Message::SysIdResult(_)));
    // The messages survive the stream encoding.
    let mut buf = [0u8; 64];
    let n = encode_message(&attitude, &mut buf).unwrap().len();
    let mut reader = MessageReader::new();
    let got: Vec<Decoded> = buf[..n].iter().filter_map(|b| reader.push(*b)).collect();
    assert_eq!(got, vec![Decoded::Message(attitude)]);
}

#[test]
fn setting_changes_are_checked_and_echoed() {
    let mut s = Settings::default();
    let find = |name: &str| PARAMS.iter().position(|p| p.name == name).unwrap();
    let (kp, proto) = (find("pid.roll.kp"), find("output.protocol"));
    let id = kp as u16;
    let (r, echo) = apply_setting(
        &mut s,
        SettingChange {
            id,
            value: f32_value(0.004),
        },
    );
    assert_eq!(r, Ok(()));
    assert_eq!(s.get(handles::PID_ROLL_KP), 0.004);
    assert_eq!(echo.unwrap().value, f32_value(0.004));
    // Out of range: refused, the echo carries the unchanged value.
    let (r, echo) = apply_setting(
        &mut s,
        SettingChange {
            id,
            value: f32_value(5.0),
        },
    );
    assert_eq!(r, Err(ParamError::OutOfRange));
    assert_eq!(echo.unwrap().value, f32_value(0.004));
    // A choice by index.
    let (r, _) = apply_setting(
        &mut s,
        SettingChange {
            id: proto as u16,
            value: 2,
        },
    );
    assert_eq!(r, Ok(()));
    assert_eq!(s.get(handles::OUTPUT_PROTOCOL), 2);
    assert_eq!(
        setting_report(&s, proto as u16),
        Some(SettingChange {
            id: proto as u16,
            value: 2
        })
    );
    let (r, echo) = apply_setting(&mut s, SettingChange { id: 999, value: 0 });
    assert_eq!((r, echo), (Err(ParamError::Unknown), None));
    assert_eq!(blocker_bit(ArmBlocker::GainsNotReady), 8);
}

#[test]
fn identification_becomes_three_messages() {
    let id = Identification {
        ln_beta: [10.0, 9.5, 6.5],
        tau_s: 0.031,
        bias: [0.0; 3],
        sigma_ln_beta: [0.01; 3],
        sigma_ln_tau: 0.02,
        gyro_noise_dps: [3.0, 4.0, 5.0],
        samples: 30_000,
    };
    let [r, p, y] = sysid_messages(&id);
    assert_eq!(r.axis, Axis::Roll);
    assert!((r.beta1 - 22_026.47).abs() < 0.5, "{r:?}");
    assert!((p.beta1 - 13_359.73).abs() < 0.5, "{p:?}");
    assert!((y.beta1 - 665.14).abs() < 0.05, "{y:?}");
    assert_eq!(
        (y.axis, y.tau_s, y.noise, y.beta2),
        (Axis::Yaw, 0.031, 25.0, 0.0)
    );
}

#[test]
fn vertical_and_cells_messages_carry_the_flight_values() {
    assert_eq!(
        vertical_message(123.456, -1.234),
        Message::Vertical(telemetry::messages::Vertical {
            altitude_cm: 12_346,
            vario_cm_s: -123,
        })
    );
    assert_eq!(
        vertical_message(f32::NAN, 1e9),
        Message::Vertical(telemetry::messages::Vertical {
            altitude_cm: 0,
            vario_cm_s: i16::MAX,
        })
    );
    let mut battery = snapshot().battery.unwrap();
    battery.cells = 0;
    assert_eq!(cells_message(&battery), None);
    battery.cells = 4;
    assert_eq!(
        cells_message(&battery),
        Some(Message::Cells(telemetry::messages::Cells { count: 4 }))
    );
}

#[test]
fn rotation_carries_altitude_vario_and_cells() {
    let snap = snapshot();
    let mut r = Reporter::new();
    let msgs: Vec<Message> = (0..2 * ROTATION.len()).map(|_| r.next(&snap)).collect();
    let vertical = Message::Vertical(telemetry::messages::Vertical {
        altitude_cm: 1_235,
        vario_cm_s: -50,
    });
    let cells = Message::Cells(telemetry::messages::Cells { count: 1 });
    // Two passes: vertical twice per pass, cells once, attitude every other message.
    assert_eq!(msgs.iter().filter(|m| **m == vertical).count(), 4);
    assert_eq!(msgs.iter().filter(|m| **m == cells).count(), 2);
    assert_eq!(
        msgs.iter()
            .filter(|m| matches!(m, Message::Attitude(_)))
            .count(),
        ROTATION.len()
    );
    // No baro (or no vertical speed yet) and no battery reading: those slots go to the next
    // kind, nothing stale or invented is sent.
    for (altitude_m, climb_mps) in [(None, Some(1.0)), (Some(3.0), None)] {
        let snap = Snapshot {
            altitude_m,
            climb_mps,
            battery: None,
            ..snapshot()
        };
        let mut r = Reporter::new();
        let msgs: Vec<Message> = (0..2 * ROTATION.len()).map(|_| r.next(&snap)).collect();
        assert!(
            msgs.iter()
                .all(|m| !matches!(m, Message::Vertical(_) | Message::Cells(_))),
            "{msgs:?}"
        );
    }
    // A battery whose cell count is not known yet sends no cells.
    let mut snap = snapshot();
    if let Some(b) = snap.battery.as_mut() {
        b.cells = 0;
    }
    let mut r = Reporter::new();
    assert!(
        (0..2 * ROTATION.len())
            .map(|_| r.next(&snap))
            .all(|m| !matches!(m, Message::Cells(_)))
    );
}
