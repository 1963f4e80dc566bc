//! The OpenLRSng receiver path against the crate's OpenLRSng transmitter state machine,
//! packet by packet (no radio): bind only in the console's window, channels and failsafe
//! into the loop as TauLink's, telemetry messages down the serial passthrough.

use super::*;
use crate::app::{BIND_WINDOW_US, Task};
use crate::settings::Settings;
use ::openlrs::RfmType;
use openlrs::channels::us_to_bits;
use openlrs::rx::Output;
use openlrs::tx::{Received, Transmitter};
use telemetry::messages::{Decoded, MessageReader};

fn openlrs_app(protocol: &str) -> FlightApp {
    let mut settings = Settings::default();
    settings.set_text("link.protocol", protocol).unwrap();
    FlightApp::new(settings, 0).unwrap()
}

/// The transmitter's bind data: 16 channels, telemetry, the given profile.
fn tx_data(version: BindingVersion, profile: u8) -> BindData {
    let mut data = BindData::defaults(version, RfmType::Mhz433);
    data.rf_magic = 0x1357_9BDF;
    data.modem_profile = profile;
    data.flags = 0x06 | 0x08;
    data
}

/// What the RX role loop hands the application for one reception.
fn events(output: Output, at_us: u64) -> heapless::Vec<RxEvent, 2> {
    let mut events = heapless::Vec::new();
    let event = match output {
        Output::Bound(data) => Some(RxEvent::Bound(data)),
        Output::Channels {
            channels_bits,
            save_failsafe,
        } => Some(RxEvent::Channels {
            channels_bits,
            save_failsafe,
            received_at_us: at_us,
        }),
        Output::Serial(bytes) => Some(RxEvent::Serial(bytes)),
        _ => None,
    };
    if let Some(event) = event {
        events.push(event).unwrap();
    }
    events
}

/// Binds `app` over OpenLRSng as the console's `bind` does; returns the stored data.
fn bind(app: &mut FlightApp, data: &BindData) -> Config {
    let mut out = heapless::String::<256>::new();
    let _ = app.on_console_line("bind", &mut out);
    let LinkStep::BindOpenLrs { config, window_us } = app.next_link_step() else {
        panic!("an OpenLRSng bind window");
    };
    assert_eq!(window_us, BIND_WINDOW_US);
    let mut rx = Receiver::new(config, None);
    rx.start(0);
    let reception = rx.on_packet(1_000, &data.bind_packet());
    let Output::Bound(bound) = reception.output else {
        panic!("the bind packet binds: {:?}", reception.output);
    };
    assert!(app.on_openlrs_bind_result(Some(&bound)));
    assert!(app.take_save().is_some(), "the bind is saved");
    config
}

struct Run {
    rx: Receiver,
    tx: Transmitter,
    reader: MessageReader,
    messages: u32,
    link_infos: u32,
    now_us: u64,
}

impl Run {
    fn new(app: &mut FlightApp, version: BindingVersion, profile: u8) -> Self {
        let data = tx_data(version, profile);
        let LinkStep::FollowOpenLrs {
            config,
            data: stored,
        } = app.next_link_step()
        else {
            panic!("the stored OpenLRSng link runs");
        };
        assert_eq!(stored, data);
        assert_eq!(config.failsafe_delay, OPENLRS_FAILSAFE_DELAY);
        let mut rx = Receiver::new(config, Some(stored));
        rx.start(0);
        Self {
            rx,
            tx: Transmitter::new(data, 0).unwrap(),
            reader: MessageReader::new(),
            messages: 0,
            link_infos: 0,
            now_us: 0,
        }
    }

    /// `duration_us` of link, every packet heard while `heard`; the loop runs at 1 kHz.
    fn run(&mut self, app: &mut FlightApp, duration_us: u64, heard: bool, channels: &[u16]) {
        let end = self.now_us + duration_us;
        let mut imu = 0u32;
        while self.now_us < end {
            self.tx.set_channels(channels);
            if let Some(send) = self.tx.poll(self.now_us) {
                self.tx.on_sent();
                if heard {
                    let reception = self.rx.on_packet(self.now_us, &send.packet);
                    let events = events(reception.output, self.now_us);
                    app.on_openlrs_step(self.now_us, &mut self.rx, &events);
                    if let Some(reply) = reception.reply {
                        match self.tx.on_downlink(&reply) {
                            Received::Serial(bytes) => {
                                for b in bytes {
                                    if let Some(Decoded::Message(_)) = self.reader.push(b) {
                                        self.messages += 1;
                                    }
                                }
                            }
                            Received::LinkInfo(_) => self.link_infos += 1,
                            _ => {}
                        }
                    }
                }
            }
            let tick = self.rx.poll(self.now_us);
            let failsafe = if tick.failsafe_started {
                heapless::Vec::from_slice(&[RxEvent::FailsafeStarted]).unwrap()
            } else {
                heapless::Vec::<RxEvent, 1>::new()
            };
            app.on_openlrs_step(self.now_us, &mut self.rx, &failsafe);
            if self.now_us.is_multiple_of(1_000) {
                let ms = (self.now_us / 1_000) as u32;
                let _ = app.on_imu_sample(ms, &crate::app::tests::resting(imu));
                imu += 1;
            }
            self.now_us += 500;
        }
    }
}

fn channels_us(throttle_us: u16) -> [u16; 16] {
    let mut bits = [us_to_bits(1500); 16];
    bits[2] = us_to_bits(throttle_us);
    bits
}

#[test]
fn an_openlrsng_link_binds_only_in_the_window_and_flies_the_loop_like_taulink() {
    for (protocol, version) in [
        ("openlrs38", BindingVersion::V38),
        ("openlrs39", BindingVersion::V39),
    ] {
        // The default profile (19 200 bit/s, 40 Hz) and the fastest (125 000 bit/s).
        for profile in [2, 4] {
            let mut app = openlrs_app(protocol);
            assert_eq!(
                app.next_link_step(),
                LinkStep::WaitForBind,
                "never bound: no link"
            );
            // A bind packet heard without the console's window is not stored.
            assert!(!app.on_openlrs_bind_result(Some(&tx_data(version, profile))));
            assert_eq!(app.next_link_step(), LinkStep::WaitForBind);
            bind(&mut app, &tx_data(version, profile));
            let mut run = Run::new(&mut app, version, profile);
            run.run(&mut app, 2_000_000, true, &channels_us(1_250));
            let input = app.link_input();
            assert!(input.up, "{protocol} profile {profile}");
            // 1250 µs is a quarter of the way up the CRSF 988…2012 µs stick.
            let expected = (1_250.0 - 988.0) / (2_012.0 - 988.0);
            assert!((input.sticks.throttle - expected).abs() < 0.01, "{input:?}");
            assert!(input.sticks.roll.abs() < 0.01);
            // Telemetry messages came down the serial passthrough, and so did the link
            // reports the transmitter shows as RSSI and LQ.
            assert!(run.messages >= 20, "{} messages", run.messages);
            assert!(run.link_infos >= 20, "{} link infos", run.link_infos);
            // Cut: failsafe within OpenLRSng's 500 ms delay (plus a slot), counted once.
            let cut_at = run.now_us;
            let mut failsafe_at = None;
            while run.now_us < cut_at + 2_000_000 {
                run.run(&mut app, 1_000, false, &channels_us(1_250));
                if failsafe_at.is_none() && !app.link_input().up {
                    failsafe_at = Some(run.now_us - cut_at);
                }
            }
            let failsafe_us = failsafe_at.expect("failsafe after the cut");
            assert!(
                (500_000..=600_000).contains(&failsafe_us),
                "{protocol} profile {profile}: failsafe after {failsafe_us} µs"
            );
            assert_eq!(app.link_failsafes(), 1);
            // Back on the air: up again.
            run.run(&mut app, 3_000_000, true, &channels_us(1_500));
            assert!(app.link_input().up, "the link comes back");
        }
    }
}

#[test]
fn every_openlrsng_step_checks_the_link_task_in() {
    let mut app = openlrs_app("openlrs39");
    let config = bind(&mut app, &tx_data(BindingVersion::V39, 2));
    let mut rx = Receiver::new(config, Some(tx_data(BindingVersion::V39, 2)));
    rx.start(0);
    // The start-up grace (every task alive for CHECK_IN_POLLS polls) runs out first.
    for k in 0..crate::app::CHECK_IN_POLLS as u32 {
        app.on_watchdog_poll(50 * k);
    }
    for t in Task::ALL {
        if t != Task::Link {
            app.check_in(t);
        }
    }
    assert!(!app.on_watchdog_poll(100));
    app.on_openlrs_step(100_000, &mut rx, &[]);
    assert!(app.on_watchdog_poll(100));
    assert!(!app.link_input().up, "nothing heard yet: failsafe");
    assert_eq!(app.link_failsafes(), 0);
}

#[test]
fn switching_the_protocol_keeps_each_links_binding() {
    let mut app = openlrs_app("openlrs39");
    bind(&mut app, &tx_data(BindingVersion::V39, 2));
    let mut out = heapless::String::<256>::new();
    let _ = app.on_console_line("set link.protocol taulink", &mut out);
    assert_eq!(
        app.next_link_step(),
        LinkStep::WaitForBind,
        "TauLink is unbound"
    );
    let _ = app.on_console_line("set link.protocol openlrs38", &mut out);
    let LinkStep::FollowOpenLrs { config, data } = app.next_link_step() else {
        panic!("the OpenLRSng bind stays");
    };
    assert_eq!(config.version, BindingVersion::V38);
    assert_eq!(data.version, 0x38);
    assert_eq!(data.rf_magic, 0x1357_9BDF);
}
