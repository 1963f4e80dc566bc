//! Issue 6 acceptance, CRSF mode: a simulated EdgeTX radio on the half-duplex JR line pings,
//! then sends RC channel frames every 4 ms; the module answers in each reply window. The
//! channels reach the flight side unchanged over the real link; the module's replies decode
//! (with the `taulink_handset` CRSF decoder) to DEVICE_INFO, the timing frame on the link's
//! packet period, LINK_STATISTICS with the flight side's uplink LQ, and BATTERY, ATTITUDE,
//! FLIGHT_MODE and GPS carrying the flight side's values.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod common;

use common::{World, flight_battery, module_now, module_settings};
use module_core::settings::{InputProtocol, OutputProtocol};
use taulink_handset::crsf::{
    Decoded, Decoder, DevicePing, Message, RcChannels, address, channels::us_to_ticks,
};

/// The radio's 16 channel pulse widths.
const WIDTHS_US: [u16; 16] = [
    988, 1500, 2012, 1013, 1751, 1102, 1899, 1357, 1000, 2000, 1500, 1500, 1200, 1800, 1499, 1501,
];
/// EdgeTX's CRSF frame period at 400 kBd before any timing frame.
const RADIO_PERIOD_US: u64 = 4_000;
/// Virtual run time.
const RUN_US: u64 = 3_000_000;

/// The radio: ping at 20 ms, channels every 4 ms after; the module's reply is read 100 µs
/// after each frame's idle line. Returns the reply bursts (virtual µs, bytes).
fn spawn_radio(world: &mut World<'_>) -> common::Shared<Vec<(u64, Vec<u8>)>> {
    let log = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let (app, time, replies) = (world.app.clone(), world.time.clone(), log.clone());
    world.executor.spawn(async move {
        let mut t = 20_000;
        let channels = RcChannels::from_us(&WIDTHS_US);
        let mut first = true;
        loop {
            time.sleep_until(t).await;
            let message = if first {
                Message::DevicePing(DevicePing {
                    destination: address::BROADCAST,
                    origin: address::RADIO,
                })
            } else {
                Message::RcChannels(channels)
            };
            first = false;
            let mut frame = [0u8; 64];
            let n = message
                .encode(address::TX_MODULE, &mut frame)
                .unwrap()
                .len();
            {
                let mut app = app.borrow_mut();
                app.on_handset_bytes(module_now(t), &frame[..n]);
                app.on_handset_idle(module_now(t + 25));
                let mut reply = [0u8; 128];
                let len = app
                    .next_handset_bytes(module_now(t + 100), &mut reply)
                    .len();
                if len > 0 {
                    replies.borrow_mut().push((t, reply[..len].to_vec()));
                }
            }
            t += RADIO_PERIOD_US;
        }
    });
    log
}

#[test]
fn crsf_channels_to_flight_and_telemetry_back_as_crsf() {
    let mut world = World::new(module_settings(InputProtocol::Crsf, OutputProtocol::Crsf));
    let replies = spawn_radio(&mut world);
    world.run_until(RUN_US);

    // --- Channels: CRSF ticks → link → flight side, bit for bit. ---
    let flight = world.flight.borrow();
    let (_, output) = flight.outputs.last().unwrap();
    let expected = WIDTHS_US.map(us_to_ticks);
    assert_eq!(*output, expected);
    let late: Vec<_> = flight
        .outputs
        .iter()
        .filter(|(t, _)| *t > 1_000_000)
        .collect();
    assert!(late.len() > 350, "{} uplinks in 2 s", late.len());
    assert!(late.iter().all(|(_, o)| *o == expected));

    // --- Replies: decode everything the module said. ---
    let mut decoder = Decoder::new();
    let mut messages = Vec::new();
    for (t, bytes) in replies.borrow().iter() {
        assert!(bytes.len() <= 128);
        for decoded in decoder.feed(bytes) {
            match decoded {
                Decoded::Frame(frame) => messages.push((*t, Message::from_frame(&frame).unwrap())),
                Decoded::Rejected(r) => panic!("reply frame rejected: {r:?}"),
            }
        }
    }
    // DEVICE_INFO first, in the ping's window, as "TauLink", serial not "ELRS".
    let (t0, Message::DeviceInfo(info)) = &messages[0] else {
        panic!("first reply is {:?}", messages[0]);
    };
    assert_eq!(*t0, 20_000);
    assert_eq!(info.name.as_str(), "TauLink");
    assert_eq!(&info.serial, b"TAUL");

    // Timing frames: the interval is the link's 4 ms slot (F250), 200 ms apart.
    let timing: Vec<_> = messages
        .iter()
        .filter_map(|(t, m)| match m {
            Message::TimingCorrection(c) => Some((*t, *c)),
            _ => None,
        })
        .collect();
    assert!(timing.len() >= 10, "{} timing frames", timing.len());
    assert!(timing.iter().all(|(_, c)| c.interval_100ns == 40_000));
    assert!(timing.windows(2).all(|w| w[1].0 - w[0].0 >= 200_000));
    // Offsets stay within half a period.
    assert!(timing.iter().all(|(_, c)| c.offset_100ns.abs() <= 20_000));

    // LINK_STATISTICS at ≥ 5 Hz; once up, the uplink LQ is the flight side's and never 0.
    let stats: Vec<_> = messages
        .iter()
        .filter_map(|(t, m)| match m {
            Message::LinkStatistics(s) => Some((*t, *s)),
            _ => None,
        })
        .collect();
    assert!(stats.len() >= 25, "{} LINK_STATISTICS in 3 s", stats.len());
    let up_from = stats
        .iter()
        .find(|(_, s)| s.uplink_lq_percent > 0)
        .unwrap()
        .0;
    assert!(up_from < 500_000, "uplink LQ > 0 only from {up_from} µs");
    let after: Vec<_> = stats.iter().filter(|(t, _)| *t >= up_from).collect();
    assert!(after.iter().all(|(_, s)| s.uplink_lq_percent > 0));
    for (_, s) in &after {
        assert!(
            flight.uplink_lq.contains(&s.uplink_lq_percent)
                || s.uplink_lq_percent == stats.last().unwrap().1.downlink_lq_percent,
            "uplink LQ {} unknown to the flight side",
            s.uplink_lq_percent
        );
    }
    let last = stats.last().unwrap().1;
    assert_eq!(last.uplink_lq_percent, 100);
    assert_eq!(last.downlink_lq_percent, 100);
    // RSSI both ways: the uplink RSSI is a value the follower measured; the downlink RSSI is
    // the module's own (its filter moves by at most 1 dB between the last reply and the end).
    for (_, s) in &after {
        let rssi = i16::from(s.uplink_rssi1_dbm);
        assert!(
            flight.uplink_rssi_dbm.contains(&rssi),
            "uplink RSSI {rssi} dBm"
        );
    }
    let link = module_core::ports::LinkPort::stats(world.app.borrow().link());
    assert!(i16::from(last.downlink_rssi_dbm).abs_diff(link.rssi_dbm) <= 1);
    // TX power: the live step of the dynamic power (on from the factory). The packet-level
    // radios keep their power, so the margin at 200 m holds and the master steps down once
    // a second from 100 mW (CRSF index 3) after the link came up: 50 mW (index 8) by 2 s,
    // 25 mW (index 2) at the end.
    let power_at = |t: u64| stats.iter().rev().find(|(at, _)| *at <= t).unwrap().1;
    assert_eq!(power_at(up_from + 900_000).uplink_tx_power_index, 3);
    assert_eq!(power_at(2_000_000).uplink_tx_power_index, 8);
    assert_eq!(last.uplink_tx_power_index, 2);
    assert_eq!(link.tx_power_step, Some(5), "+14 dBm, 25 mW");
    assert!(
        (-110..-30).contains(&link.rssi_dbm),
        "{} dBm at 200 m",
        link.rssi_dbm
    );

    // Sensors carry the flight side's values.
    let battery = messages.iter().rev().find_map(|(_, m)| match m {
        Message::Battery(b) => Some(*b),
        _ => None,
    });
    let battery = battery.unwrap();
    // 11.87 V → 119 × 0.1 V; 12.5 A → 125 × 0.1 A.
    assert_eq!(battery.voltage_dv, 119);
    assert_eq!(battery.current_da, 125);
    assert_eq!(
        battery.used_capacity_mah,
        u32::from(flight_battery().used_mah)
    );
    assert_eq!(battery.remaining_percent, 64);
    let attitude = messages
        .iter()
        .rev()
        .find_map(|(_, m)| match m {
            Message::Attitude(a) => Some(*a),
            _ => None,
        })
        .unwrap();
    // 12.50° = 0.218166 rad → 2182 × 100 µrad; −8.30° → −1449; 90° → 15708.
    assert_eq!(attitude.roll_100urad, 2182);
    assert_eq!(attitude.pitch_100urad, -1449);
    assert_eq!(attitude.yaw_100urad, 15708);
    let mode = messages
        .iter()
        .rev()
        .find_map(|(_, m)| match m {
            Message::FlightMode(f) => Some(f.clone()),
            _ => None,
        })
        .unwrap();
    assert_eq!(mode.name.as_str(), "ALTH");
    let gps = messages
        .iter()
        .rev()
        .find_map(|(_, m)| match m {
            Message::Gps(g) => Some(*g),
            _ => None,
        })
        .unwrap();
    assert_eq!(gps.latitude_e7, 473_977_420);
    assert_eq!(gps.longitude_e7, 85_455_940);
    // 12 m/s = 43.2 km/h; 488 m + 1000.
    assert_eq!(gps.groundspeed_dkmh, 432);
    assert_eq!(gps.altitude_m_plus_1000, 1488);
    assert_eq!(gps.satellites, 11);
    eprintln!(
        "uplinks {} replies {} frames {} timing {} link stats {}",
        flight.outputs.len(),
        replies.borrow().len(),
        messages.len(),
        timing.len(),
        stats.len()
    );
}

/// A radio that obeys the timing frame as EdgeTX does: the interval becomes its period, the
/// offset lengthens the next period once (positive = our frame was early). Its crystal runs
/// 50 ppm slow. Returns the end time of every channel frame on the module's clock.
fn spawn_obedient_radio(world: &mut World<'_>) -> common::Shared<Vec<u64>> {
    let log = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let (app, time, ends) = (world.app.clone(), world.time.clone(), log.clone());
    world.executor.spawn(async move {
        let channels = RcChannels::from_us(&WIDTHS_US);
        // Virtual time in ns, so the 50 ppm drift (0.2 µs per 4 ms frame) accumulates.
        let mut t_ns: u64 = 21_234_000;
        let mut period_ns: u64 = RADIO_PERIOD_US * 1_000;
        let mut decoder = Decoder::new();
        loop {
            let t = t_ns / 1_000;
            time.sleep_until(t).await;
            let mut frame = [0u8; 64];
            let n = Message::RcChannels(channels)
                .encode(address::TX_MODULE, &mut frame)
                .unwrap()
                .len();
            let mut reply = [0u8; 128];
            let len = {
                let mut app = app.borrow_mut();
                app.on_handset_bytes(module_now(t), &frame[..n]);
                app.on_handset_idle(module_now(t));
                app.next_handset_bytes(module_now(t + 100), &mut reply)
                    .len()
            };
            ends.borrow_mut().push(module_now(t));
            let mut next_ns = t_ns + period_ns;
            for decoded in decoder.feed(&reply[..len]) {
                if let Decoded::Frame(frame) = decoded
                    && let Ok(Message::TimingCorrection(c)) = Message::from_frame(&frame)
                {
                    period_ns = u64::from(c.interval_100ns) * 100 * 1_000_050 / 1_000_000;
                    next_ns = next_ns.saturating_add_signed(i64::from(c.offset_100ns) * 100);
                }
            }
            t_ns = next_ns;
        }
    });
    log
}

#[test]
fn the_timing_frame_pulls_the_radio_onto_the_air_packets() {
    let mut world = World::new(module_settings(InputProtocol::Crsf, OutputProtocol::Crsf));
    let ends = spawn_obedient_radio(&mut world);
    world.run_until(RUN_US);

    let stats = module_core::ports::LinkPort::stats(world.app.borrow().link());
    let schedule = stats.schedule.unwrap();
    assert_eq!(schedule.period_us, 4_000);
    // Where each frame ended relative to "the timing lead before an uplink's channels are
    // latched", wrapped to ±P/2.
    let period = i64::from(schedule.period_us);
    let error = |end_us: u64| {
        let lead = taulink_handset::crsf::responder::DEFAULT_TIMING_LEAD_US;
        let target = schedule.phase_us as i64 - i64::from(lead);
        let e = (end_us as i64 - target).rem_euclid(period);
        if e >= period / 2 { e - period } else { e }
    };
    let ends = ends.borrow();
    let first = error(ends[0]);
    let late: Vec<i64> = ends
        .iter()
        .filter(|&&t| t > module_now(1_000_000))
        .map(|&t| error(t))
        .collect();
    assert!(late.len() > 400);
    let worst = late.iter().map(|e| e.abs()).max().unwrap();
    // 50 ppm drifts 10 µs between 200 ms timing frames; the correction removes it each time.
    assert!(
        worst <= 12,
        "worst phase error {worst} µs (started at {first} µs)"
    );
    assert!(
        first.abs() > 100,
        "the radio started out of step ({first} µs)"
    );
    eprintln!(
        "timing: start {first} µs off, worst {worst} µs after 1 s over {} frames",
        late.len()
    );
}
