//! The module as an OpenLRSng transmitter against the crate's OpenLRSng receiver state
//! machine, packet by packet: the bind procedure after a deliberate act (a long press), the
//! handset's 16 channels at the receiver, telemetry records from the receiver's serial
//! passthrough at the handset with OpenLRSng's RSSI and link quality in the link statistics,
//! and the receiver's failsafe when the handset input stops. At OpenLRSng's default profile
//! (19 200 bit/s) and its fastest (125 000 bit/s), binding versions 3.8 and 3.9.

#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

use module_core::air::AirLink;
use module_core::air::openlrs::OPENLRS_RATE_CODE_BASE;
use module_core::app::{Action, App};
use module_core::button::ButtonEvent;
use module_core::channels::{ChannelFrame, us_to_ticks};
use module_core::ports::{HandsetOutput, LinkPort, LinkStats};
use module_core::session::{BindOutcome, LinkStep, SessionEnd};
use module_core::settings::{InputProtocol, LinkProtocol, OpenLrsSettings, Settings};
use openlrs::BindingVersion;
use openlrs::bind::DEFAULT_RF_MAGIC;
use openlrs::channels::bits_to_us;
use openlrs::roles::TxEvent;
use openlrs::rx::{Config, Output, Receiver};
use openlrs::tx::Transmitter;
use radio_rfm22b::RfmType;

#[derive(Default)]
struct Handset {
    telemetry: Vec<Vec<u8>>,
}

impl HandsetOutput for Handset {
    fn on_telemetry(&mut self, record: &[u8]) {
        self.telemetry.push(record.to_vec());
    }
    fn on_link_stats(&mut self, _stats: &LinkStats) {}
}

type Module = App<AirLink, Handset>;

/// The handset's sticks: channel i at 1000 + 60·i µs.
fn handset_us() -> [u16; 16] {
    std::array::from_fn(|i| 1000 + 60 * i as u16)
}

/// A telemetry record as the flight side sends it down (a battery message).
fn record() -> Vec<u8> {
    let message = telemetry::messages::Message::Battery(telemetry::messages::Battery {
        voltage_mv: 11_870,
        current_ca: 1234,
        used_mah: 456,
        remaining_percent: 71,
    });
    let mut out = [0u8; 64];
    module_core::records::encode(&message, &mut out)
        .unwrap()
        .to_vec()
}

fn stream_frame(record: &[u8]) -> Vec<u8> {
    let mut out = [0u8; 80];
    module_core::records::to_stream(record, &mut out)
        .unwrap()
        .to_vec()
}

/// Binds the module (long press) with a receiver that has no bind data; returns the link
/// the module flies afterwards.
fn bind(app: &mut Module, version: BindingVersion) -> openlrs::BindData {
    app.on_radio_present(true);
    let LinkStep::RunOpenLrsTx(factory) = app.next_link_step(0, 7) else {
        panic!("an OpenLRSng transmitter flies from the start");
    };
    assert_eq!(
        factory.rf_magic, DEFAULT_RF_MAGIC,
        "OpenLRSng's factory link"
    );
    // Nothing binds without the owner: a long press.
    assert_eq!(app.poll_session(10), None);
    app.on_button(ButtonEvent::LongPress);
    let end = app.poll_session(20).unwrap();
    assert_eq!(end, SessionEnd::BindRequested);
    app.on_session_end(end);
    let LinkStep::BindOpenLrsTx { data, .. } = app.next_link_step(30, 0x00C0_FFEE) else {
        panic!("OpenLRSng's bind procedure");
    };
    assert_ne!(
        data.rf_magic, DEFAULT_RF_MAGIC,
        "the bind gives the link its own magic"
    );
    let mut rx = Receiver::new(Config::new(version, RfmType::Mhz433), None);
    rx.start(0);
    let reception = rx.on_packet(1_000, &data.bind_packet());
    assert_eq!(reception.output, Output::Bound(data));
    let Some(Action::Save(saved)) = app.on_bind_outcome(BindOutcome::OpenLrs { accepted: true })
    else {
        panic!("the bind is saved");
    };
    assert_eq!(saved.openlrs.hop_seed, 0x00C0_FFEE);
    assert_eq!(app.next_link_step(40, 1), LinkStep::Probe);
    app.on_radio_present(true);
    let LinkStep::RunOpenLrsTx(flown) = app.next_link_step(50, 2) else {
        panic!("the bound link runs");
    };
    assert_eq!(
        flown, data,
        "the same link after the bind (and after a reboot)"
    );
    flown
}

#[test]
fn the_module_binds_and_flies_an_openlrsng_receiver() {
    for (protocol, version) in [
        (LinkProtocol::OpenLrs38, BindingVersion::V38),
        (LinkProtocol::OpenLrs39, BindingVersion::V39),
    ] {
        for profile in [2u8, 4] {
            let settings = Settings {
                protocol,
                input: InputProtocol::Crsf,
                openlrs: OpenLrsSettings {
                    profile,
                    channel_mode: 6,
                    ..OpenLrsSettings::default()
                },
                ..Settings::default()
            };
            let mut app = App::new(settings, AirLink::new(), Handset::default(), false).unwrap();
            let data = bind(&mut app, version);
            assert_eq!(data.modem_profile, profile);
            let mut tx = Transmitter::new(data, 0).unwrap().with_stale_input_stop();
            let mut rx = Receiver::new(
                Config {
                    bind_window_us: None,
                    ..Config::new(version, RfmType::Mhz433)
                },
                Some(data),
            );
            rx.start(0);
            let sticks = ChannelFrame::from_ticks(&handset_us().map(us_to_ticks));
            let telemetry = record();
            let mut heard = Vec::new();
            let input_until = 3_000_000u64;
            let mut failsafe_at = None;
            let mut now = 0u64;
            let mut next_message_us = 0u64;
            while now < 6_000_000 {
                // The handset's CRSF frames every 4 ms, until it stops at 3 s.
                if now < input_until && now.is_multiple_of(4_000) {
                    app.on_handset_channels(&sticks);
                }
                if now >= tx.next_deadline_us() {
                    app.on_openlrs_send(&mut tx);
                    let mut events = Vec::new();
                    if let Some(send) = tx.poll(now) {
                        tx.on_sent();
                        let reception = rx.on_packet(now, &send.packet);
                        if let Output::Channels { channels_bits, .. } = reception.output {
                            heard.push(channels_bits);
                        }
                        // A message every 100 ms: the flight side leaves room between them
                        // for the receiver's link reports.
                        if now >= next_message_us && rx.serial_free() == 32 {
                            rx.queue_serial(&stream_frame(&telemetry));
                            next_message_us = now + 100_000;
                        }
                        match reception.reply {
                            Some(reply) => events.push(TxEvent::Downlink {
                                received: tx.on_downlink(&reply),
                                rssi: 180,
                            }),
                            None => events.push(TxEvent::ReplyMissed),
                        }
                    }
                    app.on_openlrs_step(now, (now / 1_000) as u32, &tx, &events);
                }
                let tick = rx.poll(now);
                if tick.failsafe_started && failsafe_at.is_none() {
                    failsafe_at = Some(now);
                }
                if now == 2_000_000 {
                    let stats = app.link().stats();
                    assert!(stats.connected, "{stats:?}");
                    assert_eq!(stats.remote_link_quality_percent, Some(100));
                    assert_eq!(stats.link_quality_percent, 100);
                    assert_eq!(stats.rate_code, OPENLRS_RATE_CODE_BASE + profile);
                    app.on_tick();
                }
                now += 500;
            }
            // Every channel packet carried the handset's 16 channels.
            assert!(heard.len() > 60, "{} packets", heard.len());
            for bits in &heard {
                let us: Vec<u16> = bits.iter().map(|b| bits_to_us(*b)).collect();
                assert_eq!(us, handset_us(), "{protocol:?} profile {profile}");
            }
            // Telemetry came through the serial passthrough to the handset.
            let handset = app.handset();
            assert!(handset.telemetry.len() > 10, "{}", handset.telemetry.len());
            assert!(handset.telemetry.iter().all(|r| *r == telemetry));
            // The handset stopped at 3 s: the transmitter goes quiet after the input
            // timeout (500 ms) and eight stale packets, and the receiver's failsafe follows
            // OpenLRSng's 1 s delay.
            let failsafe = failsafe_at.expect("failsafe after the handset stopped") - 3_000_000;
            assert!(
                (1_500_000..=1_900_000).contains(&failsafe),
                "{protocol:?} profile {profile}: failsafe {failsafe} µs after the input stopped"
            );
        }
    }
}
