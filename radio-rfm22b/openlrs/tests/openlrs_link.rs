//! Both OpenLRSng roles looped together in virtual time over an ideal "air" that honours the
//! hop index (the header check) and can drop packets: bind, 16 channels at the right interval,
//! re-hop after a miss, slow-hop re-acquisition, failsafe, telemetry and serial both ways, and
//! a 3.8 TX refused by a 3.9 RX.
// The helpers below are test code too.
#![allow(clippy::unwrap_used, clippy::collapsible_if)]

use openlrs::rx::{self, Command, Output, Receiver};
use openlrs::tx::{BindBeacon, Received, Transmitter};
use openlrs::{BindData, BindingVersion, RfmType, timing};

const STEP_US: u64 = 100;

/// Where the RX listens: the bind channel or a hop index of the link.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Listening {
    Bind,
    Hop(u8),
}

fn apply(cmd: Option<Command>, listening: &mut Listening) {
    match cmd {
        Some(Command::ListenBind) => *listening = Listening::Bind,
        Some(Command::StartLink(_)) => *listening = Listening::Hop(0),
        Some(Command::Hop(i)) => *listening = Listening::Hop(i),
        None => {}
    }
}

/// Binds a TX of `tx_version` with an RX of `rx_version`; returns the RX's bind data.
fn bind(
    tx_version: BindingVersion,
    rx_version: BindingVersion,
    data: BindData,
) -> (Receiver, Option<BindData>, Vec<Output>) {
    let mut rx = Receiver::new(rx::Config::new(rx_version, RfmType::Mhz433), None);
    let mut listening = Listening::Bind;
    apply(Some(rx.start(0)), &mut listening);
    let mut data = data;
    data.version = tx_version.byte();
    let mut beacon = BindBeacon::new(&data, 0);
    let mut outputs = Vec::new();
    for t in (0..2_000_000).step_by(STEP_US as usize) {
        if let Some(packet) = beacon.poll(t) {
            if listening == Listening::Bind {
                let r = rx.on_packet(t, packet);
                if let Some(reply) = &r.reply {
                    beacon.on_packet(reply);
                }
                apply(r.command, &mut listening);
                outputs.push(r.output);
            }
        }
        if beacon.acknowledged() {
            break;
        }
    }
    let bound = rx.bind_data().copied();
    (rx, bound, outputs)
}

struct Run {
    rx_times: Vec<u64>,
    rx_channels: Vec<Vec<u16>>,
    failsafe_at: Option<u64>,
    tx_infos: Vec<u8>,
    tx_serial: Vec<u8>,
    rx_serial: Vec<u8>,
    /// Uplink packets sent, not dropped, that arrive before the end of the run.
    deliverable: usize,
}

/// Runs the link for `duration_us`; `drop(n, t)` says whether uplink packet n is lost.
fn run_link(
    rx: &mut Receiver,
    data: BindData,
    duration_us: u64,
    channels: &[u16],
    drop: impl Fn(usize, u64) -> bool,
) -> Run {
    let mut tx = Transmitter::new(data, 0).unwrap();
    tx.set_channels(channels);
    tx.queue_serial(b"uplink serial!");
    rx.queue_serial(b"downlink data");
    rx.on_rssi_sample(180);
    rx.set_afc(300);
    rx.set_analog_inputs(10, 20);
    let mut listening = Listening::Hop(0);
    let mut run = Run {
        rx_times: vec![],
        rx_channels: vec![],
        failsafe_at: None,
        tx_infos: vec![],
        tx_serial: vec![],
        rx_serial: vec![],
        deliverable: 0,
    };
    let mut sent = 0usize;
    let mode = data.channel_mode();
    let bps = openlrs::modem::profile(data.modem_profile).unwrap().bps;
    let airtime = u64::from(timing::airtime_us(mode.packet_size(), bps, false));
    let mut in_flight: Option<(u64, u8, Vec<u8>)> = None;
    for t in (0..duration_us).step_by(STEP_US as usize) {
        let tick = rx.poll(t);
        apply(tick.command, &mut listening);
        if tick.failsafe_started {
            run.failsafe_at = Some(t);
        }
        if let Some(send) = tx.poll(t) {
            tx.on_sent();
            if !drop(sent, t) {
                if t + airtime < duration_us {
                    run.deliverable += 1;
                }
                in_flight = Some((t + airtime, send.hop_index, send.packet.to_vec()));
            }
            sent += 1;
        }
        if let Some((arrival, hop, packet)) = in_flight.clone() {
            if t >= arrival {
                in_flight = None;
                if listening == Listening::Hop(hop) {
                    let r = rx.on_packet(t, &packet);
                    match r.output {
                        Output::Channels { channels_bits, .. } => {
                            run.rx_times.push(t);
                            run.rx_channels.push(channels_bits.to_vec());
                        }
                        Output::Serial(bytes) => run.rx_serial.extend_from_slice(&bytes),
                        _ => {}
                    }
                    if let Some(reply) = r.reply {
                        match tx.on_downlink(&reply) {
                            Received::LinkInfo(info) => run.tx_infos.push(info.link_quality),
                            Received::Serial(bytes) => run.tx_serial.extend_from_slice(&bytes),
                            _ => {}
                        }
                    }
                    apply(r.command, &mut listening);
                }
            }
        }
    }
    run
}

fn sixteen_channel_data() -> BindData {
    let mut d = BindData::defaults(BindingVersion::V38, RfmType::Mhz433);
    d.flags = 0x0E; // 16 channels, serial telemetry
    d
}

#[test]
fn binds_and_carries_16_channels_at_the_interval() {
    let data = sixteen_channel_data();
    let (mut rx, bound, _) = bind(BindingVersion::V38, BindingVersion::V38, data);
    assert_eq!(bound, Some(data));
    let interval = timing::interval_us(&data).unwrap();
    assert_eq!(interval, 29_000);
    let channels: Vec<u16> = (0..16).map(|i| 12 + 60 * i).collect();
    let run = run_link(&mut rx, data, 2_000_000, &channels, |_, _| false);
    // The RX starts on hop 0, the TX's first packet is on hop 0: nothing is lost.
    let serial_packets = run.rx_serial.len().div_ceil(8);
    assert_eq!(run.rx_times.len() + serial_packets, run.deliverable);
    assert!(run.deliverable >= 68, "{}", run.deliverable);
    assert!(run.rx_channels.iter().all(|c| *c == channels));
    // Every RC packet follows the previous uplink packet by whole intervals.
    for w in run.rx_times.windows(2) {
        assert_eq!((w[1] - w[0]) % u64::from(interval), 0, "{w:?}");
    }
    assert_eq!(run.failsafe_at, None);
    assert_eq!(run.rx_serial, b"uplink serial!");
    assert_eq!(run.tx_serial, b"downlink data");
    assert_eq!(*run.tx_infos.last().unwrap(), 15);
    assert_eq!(rx.link_quality(), 15);
}

#[test]
fn one_missed_packet_costs_one_packet() {
    let mut data = sixteen_channel_data();
    data.flags = 0x06; // no telemetry: every packet is RC
    let (mut rx, _, _) = bind(BindingVersion::V39, BindingVersion::V39, data);
    let interval = u64::from(timing::interval_us(&data).unwrap());
    assert_eq!(interval, 18_000);
    let run = run_link(&mut rx, data, 1_000_000, &[512; 16], |n, _| n == 10);
    // Every packet but the dropped one arrives: the RX re-hopped in time for the next.
    assert_eq!(run.rx_times.len(), run.deliverable);
    assert_eq!(run.deliverable, 1_000_000usize / interval as usize - 1);
    let gap = run.rx_times.windows(2).map(|w| w[1] - w[0]).max().unwrap();
    assert_eq!(gap, 2 * interval);
    assert_eq!(rx.link_quality(), 15);
}

#[test]
fn long_loss_triggers_failsafe_then_slow_hop_reacquires() {
    let mut data = sixteen_channel_data();
    data.flags = 0x06;
    let (mut rx, _, _) = bind(BindingVersion::V38, BindingVersion::V38, data);
    let interval = u64::from(timing::interval_us(&data).unwrap());
    // TX silent from 0.5 s to 2.0 s.
    let run = run_link(&mut rx, data, 4_000_000, &[700; 16], |_, t| {
        (500_000..2_000_000).contains(&t)
    });
    let last_before = *run.rx_times.iter().rfind(|&&t| t < 2_000_000).unwrap();
    assert!(last_before < 500_000 + interval, "{last_before}");
    let failsafe = run.failsafe_at.unwrap();
    // First miss noticed at last + interval + 1000 µs; failsafe 1.0 s (delay code 10) later.
    let first_miss = last_before + interval + 1000;
    assert!(
        failsafe > first_miss + 1_000_000 && failsafe <= first_miss + 1_000_000 + 2 * STEP_US,
        "{failsafe} vs {first_miss}"
    );
    let first_after = *run.rx_times.iter().find(|&&t| t >= 2_000_000).unwrap();
    // Slow hopping dwells interval·hopcount per channel: the TX comes round within a cycle
    // of hop cycles.
    assert!(first_after < 2_000_000 + 6 * 6 * interval, "{first_after}");
    assert!(!rx.failsafe_active());
}

#[test]
fn v38_tx_and_v39_rx_refuse_each_other() {
    let data = sixteen_channel_data();
    let (rx, bound, outputs) = bind(BindingVersion::V38, BindingVersion::V39, data);
    assert_eq!(bound, None);
    assert!(!rx.is_linked());
    assert!(!outputs.is_empty());
    assert!(outputs.iter().all(|o| matches!(
        o,
        Output::BindRefused(openlrs::bind::BindReception::WrongVersion { found: 0x38 })
    )));
    let (_, bound, _) = bind(BindingVersion::V39, BindingVersion::V38, data);
    assert_eq!(bound, None);
}
