//! The OpenLRSng transmitter role (`openlrs::tx`): downlink frames as the RX
//! (or anyone on the channel) sends them, fed to the TX with its own polls, channel input,
//! serial input and failsafe button; what it learns goes on to the handset encoders
//! (`frsky::HandsetTelemetry`); and bind-mode replies into the `BindBeacon`.
//!
//! Invariants: every uplink has the mode's packet size, uses a hop of the list and parses
//! back as the channels last set (10-bit) or as 1..=8 serial bytes; downlink serial is
//! 1..=8 bytes; the hub and S.Port bytes for the handset decode as whole frames with the
//! handset decoders; the beacon is acknowledged exactly by a packet starting with 'B'.
#![no_main]

use libfuzzer_sys::fuzz_target;
use openlrs::bind::BIND_ACK;
use openlrs::channels::MAX_CHANNELS;
use openlrs::frsky::HandsetTelemetry;
use openlrs::tx::{BindBeacon, Received, Transmitter};
use openlrs::uplink::{self, Uplink};
use taulink_fuzz::Input;
use taulink_handset::{frsky_d, sport};

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let (version, band) = taulink_fuzz::openlrs_link(&mut input);
    let mut bind = taulink_fuzz::openlrs_bind(&mut input, version, band);
    let hops = usize::from(input.u8() % 25);
    for (slot, &ch) in bind.hop_channels.iter_mut().zip(input.bytes(hops)) {
        *slot = ch % 50;
    }
    let Ok(tx) = Transmitter::new(bind, 0) else {
        return;
    };
    let mut tx = if input.bool() {
        tx.with_stale_input_stop()
    } else {
        tx
    };
    let mode = bind.channel_mode();
    let mut channels = [512u16; MAX_CHANNELS];
    let mut handset = HandsetTelemetry::default();
    let mut beacon = BindBeacon::new(&bind, 0);
    let mut acked = false;
    let mut now = 0u64;
    while !input.is_empty() {
        now = now.saturating_add(u64::from(input.u16()));
        match input.u8() % 8 {
            0 | 1 => {
                if let Some(send) = tx.poll(now) {
                    assert_eq!(send.packet.len(), mode.packet_size());
                    assert!(usize::from(send.hop_index) < bind.hop_count());
                    match uplink::parse(mode, &send.packet) {
                        Uplink::Servo { channels_bits, .. } => {
                            let exact = 4 * mode.full_groups();
                            for (got, set) in channels_bits.iter().zip(&channels).take(exact) {
                                assert_eq!(*got, set & 0x3FF);
                            }
                        }
                        Uplink::Serial { data, .. } => assert!((1..=8).contains(&data.len())),
                        other => panic!("the TX sent {other:?}"),
                    }
                    tx.on_sent();
                }
            }
            2 | 3 => match tx.on_downlink(input.chunk(12)) {
                Received::LinkInfo(info) => handset.on_link_info(info, input.u8()),
                Received::Serial(bytes) => {
                    assert!((1..=8).contains(&bytes.len()));
                    handset.on_serial(&bytes);
                }
                Received::Duplicate | Received::Invalid(_) => {}
            },
            4 => {
                for value in channels.iter_mut() {
                    *value = input.u16() & 0x3FF;
                }
                tx.set_channels(&channels);
                tx.set_save_failsafe(input.bool());
            }
            5 => {
                tx.queue_serial(input.chunk(80));
            }
            6 => {
                let quality = tx.link_quality();
                assert!(quality <= 15);
                let hub = handset.hub_tick(quality);
                let mut decoder = frsky_d::Decoder::new();
                decoder.push_all(&hub, |event| {
                    assert!(matches!(event, frsky_d::Event::Frame(_)), "hub {event:?}")
                });
                let port = handset.smartport_tick(quality, input.u8() % 4);
                let mut decoder = sport::Decoder::new();
                decoder.push_all(&port, |event| {
                    assert!(
                        !matches!(event, sport::Event::Rejected(_)),
                        "S.Port {event:?}"
                    )
                });
            }
            _ => {
                let packet = input.chunk(4);
                acked |= packet.first() == Some(&BIND_ACK);
                assert_eq!(beacon.on_packet(packet), acked);
                if let Some(bind_packet) = beacon.poll(now) {
                    assert!(!acked);
                    assert_eq!(bind_packet, &bind.bind_packet());
                }
            }
        }
    }
});
