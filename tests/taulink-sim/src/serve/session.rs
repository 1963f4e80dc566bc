//! One ground-station connection's world: both link ends on packet-level radios in a fresh
//! simulated medium, the module end relaying the downlink telemetry through the HM-10
//! relay of `module_core` (what the phone would receive) and the phone's frames back onto
//! the uplink, the flight end reporting with `flight_core::report` over a scripted flight
//! ([`super::flight`]) and applying setting changes to a real `flight_core` settings table.
//! Advanced by the caller in steps of virtual time.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;

use module_core::hm10::Relay;
use module_core::hm10::relay::{MAX_FRAME_LEN, MAX_RECORD_LEN};
use module_core::records::{self, MAX_STREAM_FRAME_LEN, Splitter};
use telemetry::channels::{CHANNEL_MAX, FailsafeValues};
use telemetry::link::LinkKey;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::run_follower;
use telemetry::link::master::{MasterHooks, run_master};
use telemetry::mock::{
    ChannelModel, Executor, Medium, MockClock, MockRadio, Node, SplitMix64, VirtualTime,
};

use super::flight::{FlightSide, Sent};
use crate::Scenario;
use crate::world::params_for;

/// The binding phrase both ends of a served world carry (spec §12): the page signs setting
/// changes with it. Printed with the URL; a demo value, public by design.
pub const SERVE_PHRASE: &str = "taulink demo";

/// Bytes waiting for the page; beyond this the oldest are dropped (a stalled page must not
/// grow the server).
pub const TO_PAGE_MAX: usize = 64 * 1024;
/// Bytes from the page waiting for the relay.
pub const FROM_PAGE_MAX: usize = 4 * 1024;

/// The byte pipes between the page and the module end.
#[derive(Debug, Default)]
pub struct Pipes {
    /// Relay frames for the page.
    pub to_page: VecDeque<u8>,
    /// Bytes from the page for the relay.
    pub from_page: VecDeque<u8>,
}

/// The module's side: stream → records → HM-10 relay → page, and back.
struct ModuleSide {
    pipes: Rc<RefCell<Pipes>>,
    splitter: Splitter,
    relay: Relay,
}

impl MasterHooks for ModuleSide {
    fn on_slot(&mut self, _now_us: u64, master: &mut Master) {
        // Sticks centred, throttle low: the page does not fly.
        let mut channels = [CHANNEL_MAX / 2; 16];
        if let Some(throttle) = channels.get_mut(2) {
            *throttle = 0;
        }
        master.set_channels(&channels);
        let mut pipes = self.pipes.borrow_mut();
        let mut buf = [0u8; 64];
        let mut record = [0u8; MAX_RECORD_LEN];
        loop {
            let n = master.downlink_stream.read(&mut buf);
            if n == 0 {
                break;
            }
            for &b in buf.iter().take(n) {
                if let Some(len) = self.splitter.push(b, &mut record) {
                    self.relay
                        .on_link_record(record.get(..len).unwrap_or_default());
                }
            }
        }
        let mut frame = [0u8; MAX_FRAME_LEN];
        while let Some(n) = self.relay.next_frame_to_phone(&mut frame) {
            pipes.to_page.extend(frame.get(..n).unwrap_or_default());
        }
        let excess = pipes.to_page.len().saturating_sub(TO_PAGE_MAX);
        pipes.to_page.drain(..excess);
        let from_page: Vec<u8> = pipes.from_page.drain(..).collect();
        self.relay.on_phone_bytes(&from_page);
        while master.uplink_stream.free() >= MAX_STREAM_FRAME_LEN {
            let Some(len) = self.relay.next_record_to_flight(&mut record) else {
                break;
            };
            let mut out = [0u8; MAX_STREAM_FRAME_LEN];
            if let Ok(n) = records::to_stream(record.get(..len).unwrap_or_default(), &mut out) {
                master.uplink_stream.write(out.get(..n).unwrap_or_default());
            }
        }
    }
}

/// One simulated world for one page.
pub struct Session {
    executor: Executor<'static>,
    time: VirtualTime,
    /// Pipes to and from the page.
    pub pipes: Rc<RefCell<Pipes>>,
    /// What the flight side sent and applied.
    pub sent: Rc<RefCell<Sent>>,
}

impl Session {
    /// A world for `s` (its rate, band, distance, loss, seed; always bound, packet level).
    pub fn new(s: &Scenario) -> Self {
        let time = VirtualTime::new();
        let model = ChannelModel {
            loss: s.loss,
            bit_error_rate: s.bit_error_rate,
            ..ChannelModel::default()
        };
        let medium = Medium::new(time.clone(), model, s.seed);
        let params = params_for(s, SplitMix64::new(s.seed).next_u64() as u32);
        let module_node = medium.add_node(Node::default());
        let flight_node = medium.add_node(Node {
            position_m: s.distance_m,
            ..Node::default()
        });
        let pipes = Rc::new(RefCell::new(Pipes::default()));
        let sent = Rc::new(RefCell::new(Sent::default()));
        let mut executor = Executor::new(time.clone());
        let mut module = ModuleSide {
            pipes: pipes.clone(),
            splitter: Splitter::new(),
            relay: Relay::new(true),
        };
        let (m_medium, m_time) = (medium.clone(), time.clone());
        executor.spawn(async move {
            let mut radio = MockRadio::new(m_medium, module_node);
            let mut clock = MockClock::new(m_time, 1_234_567);
            let mut master = Master::new(params).with_key(LinkKey::from_phrase(SERVE_PHRASE));
            let _ = run_master(&mut radio, &mut clock, &mut master, &mut module).await;
        });
        let mut flight = FlightSide::new(
            sent.clone(),
            LinkKey::from_phrase(SERVE_PHRASE),
            SplitMix64::new(s.seed ^ 0x5E55).next_u64() as u32,
        );
        let failsafe_us = s.failsafe_ms * 1000;
        let f_time = time.clone();
        executor.spawn(async move {
            let mut radio = MockRadio::new(medium, flight_node);
            let mut clock = MockClock::new(f_time, 0);
            let mut follower = Follower::new(params, FailsafeValues::default(), failsafe_us)
                .with_key(LinkKey::from_phrase(SERVE_PHRASE));
            let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut flight).await;
        });
        Self {
            executor,
            time,
            pipes,
            sent,
        }
    }

    /// Virtual time, µs.
    pub fn now_us(&self) -> u64 {
        self.time.now_us()
    }

    /// Runs the world up to `t_us`.
    pub fn run_until(&mut self, t_us: u64) {
        self.executor.run_until(t_us);
    }

    /// Bytes from the page, for the relay (bounded: the excess is dropped, as a UART would).
    pub fn from_page(&self, bytes: &[u8]) {
        let mut pipes = self.pipes.borrow_mut();
        let room = FROM_PAGE_MAX.saturating_sub(pipes.from_page.len());
        pipes.from_page.extend(bytes.iter().take(room));
    }

    /// Everything waiting for the page.
    pub fn take_to_page(&self) -> Vec<u8> {
        self.pipes.borrow_mut().to_page.drain(..).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use telemetry::change_auth::Signer;
    use telemetry::messages::{Decoded, Message, MessageReader, RefuseReason, encode_message};

    fn page_messages(session: &Session, reader: &mut MessageReader) -> Vec<Message> {
        session
            .take_to_page()
            .iter()
            .filter_map(|&b| reader.push(b))
            .map(|d| match d {
                Decoded::Message(m) => m,
                Decoded::Dropped => panic!("the relay stream lost a frame"),
            })
            .collect()
    }

    /// `SettingChange` of pid.roll.kp to `value`.
    fn kp(value: f32) -> telemetry::messages::SettingChange {
        let id = flight_core::settings::PARAMS
            .iter()
            .position(|p| p.name == "pid.roll.kp")
            .unwrap();
        telemetry::messages::SettingChange {
            id: id as u16,
            value: flight_core::report::f32_value(value),
        }
    }

    #[test]
    fn the_page_gets_the_flight_sides_telemetry_and_its_setting_round_trips() {
        let mut session = Session::new(&Scenario::default());
        let mut reader = MessageReader::new();
        session.run_until(3_000_000);
        let got = page_messages(&session, &mut reader);
        for kind in [
            "Attitude",
            "Battery",
            "LinkStats",
            "FlightMode",
            "ArmState",
            "Gps",
        ] {
            assert!(
                got.iter().any(|m| format!("{m:?}").starts_with(kind)),
                "no {kind} in {} messages",
                got.len()
            );
        }
        // The last battery the page got is what the flight side last sent.
        let last_battery = got.iter().rev().find(|m| matches!(m, Message::Battery(_)));
        let sent = session.sent.borrow().last.get("Battery").cloned();
        assert_eq!(
            last_battery.map(|m| serde_json::to_value(m).unwrap()["Battery"].clone()),
            sent
        );

        // pid.roll.kp to 0.004, unsigned: refused, nothing applied.
        let change = kp(0.004);
        let send = |session: &mut Session, message: Message| {
            let mut frame = [0u8; 32];
            let n = encode_message(&message, &mut frame).unwrap();
            session.from_page(&frame[..n]);
        };
        send(&mut session, Message::SettingChange(change));
        session.run_until(4_000_000);
        assert!(session.sent.borrow().applied.is_empty());
        let answer = page_messages(&session, &mut reader);
        let Some(Message::ChangeRefused(refused)) = answer
            .iter()
            .find(|m| matches!(m, Message::ChangeRefused(_)))
        else {
            panic!("no refusal in {answer:?}");
        };
        assert_eq!(refused.reason, RefuseReason::NotAuthenticated);
        // Signed with the served world's phrase, after learning the session: applied.
        let mut phone = Signer::new(&LinkKey::from_phrase(SERVE_PHRASE));
        assert!(phone.on_refused(refused));
        send(&mut session, Message::SignedChange(phone.sign(change)));
        session.run_until(5_000_000);
        assert_eq!(session.sent.borrow().applied, vec![change]);
        let echoed = page_messages(&session, &mut reader);
        assert!(echoed.contains(&Message::SettingChange(change)), "no echo");
    }

    #[test]
    fn while_armed_a_change_is_refused_with_the_reason() {
        let mut session = Session::new(&Scenario::default());
        let mut reader = MessageReader::new();
        // The script arms at 20 s.
        session.run_until(21_000_000);
        let _ = page_messages(&session, &mut reader);
        let mut phone = Signer::new(&LinkKey::from_phrase(SERVE_PHRASE));
        let mut frame = [0u8; 32];
        let n = encode_message(&Message::SignedChange(phone.sign(kp(0.004))), &mut frame).unwrap();
        session.from_page(&frame[..n]);
        session.run_until(22_000_000);
        assert!(session.sent.borrow().applied.is_empty());
        assert!(
            page_messages(&session, &mut reader)
                .iter()
                .any(|m| matches!(m, Message::ChangeRefused(r) if r.reason == RefuseReason::Armed))
        );
    }
}
