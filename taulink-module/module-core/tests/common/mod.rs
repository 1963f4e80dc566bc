//! The end-to-end harness: the module core (`App` with `AirLink` and `Handset`) driving the
//! real `telemetry::link` master over telemetry's packet-level mock radio, against a flight
//! side running the real follower, all in virtual time. The module's firmware clock is the
//! master's link clock (as on the nRF52840, where both are embassy-time).

#![allow(dead_code)]

use std::cell::RefCell;
use std::rc::Rc;

use module_core::air::{AirLink, link_params};
use module_core::app::App;
use module_core::handset::Handset;
use module_core::session::LinkStep;
use module_core::settings::{Band, InputProtocol, OutputProtocol, RateMode, Role, Settings};
use telemetry::channels::{Channels as LinkChannels, FailsafeValues};
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{FollowerHooks, run_follower};
use telemetry::link::master::{MasterHooks, run_master};
use telemetry::messages::{
    Attitude, Battery, FlightMode, Gps, GpsFix, LinkStats, Message, MessageReader, encode_message,
};
use telemetry::mock::{ChannelModel, Executor, Medium, MockRadio, Node, SimClock, VirtualTime};

/// Offset of the module's clock from virtual time (it booted earlier).
pub const MODULE_EPOCH_US: u64 = 1_234_567;
/// Offset of the flight controller's clock.
pub const FLIGHT_EPOCH_US: u64 = 987_654_321;
/// The bind ID both ends share.
pub const BIND_ID: u32 = 0x5EED_1234;

/// The module core under test.
pub type ModuleApp = App<AirLink, Handset>;
/// Shared handle.
pub type Shared<T> = Rc<RefCell<T>>;

/// What the flight controller sends: a 3S pack at 11.87 V, attitude, altitude hold, GPS.
pub fn flight_battery() -> Battery {
    Battery {
        voltage_mv: 11_870,
        current_ca: 1_250,
        used_mah: 420,
        remaining_percent: 64,
    }
}

/// Attitude the flight side reports.
pub fn flight_attitude() -> Attitude {
    Attitude {
        roll_cdeg: 1_250,
        pitch_cdeg: -830,
        yaw_cdeg: 9_000,
    }
}

/// GPS fix the flight side reports.
pub fn flight_gps() -> Gps {
    Gps {
        latitude_e7: 473_977_420,
        longitude_e7: 85_455_940,
        altitude_cm: 48_800,
        ground_speed_cm_s: 1_200,
        course_cdeg: 27_000,
        satellites: 11,
        fix: GpsFix::Fix3d,
    }
}

/// Transmitter settings, bound, at 125 kbit/s (the link's F250 mode, 4 ms slots), on the
/// unauthenticated link (the explicit `plain` setting): these tests are about the handset
/// and telemetry paths, which run the same keyed or not; `bind_over_the_air` and the
/// simulators run keyed links.
pub fn module_settings(input: InputProtocol, output: OutputProtocol) -> Settings {
    Settings {
        role: Role::Transmitter,
        rate: RateMode::F250,
        input,
        output,
        band: Band::Mhz433,
        tx_power: 7,
        bind_id: BIND_ID,
        plain: true,
        ..Settings::default()
    }
}

/// The flight side: the follower's outputs, telemetry out every 100 ms, messages in.
#[derive(Default)]
pub struct FlightSide {
    /// Channel outputs after every new uplink: (virtual µs, values).
    pub outputs: Vec<(u64, LinkChannels)>,
    /// Messages received from the module (phone → flight).
    pub received: Vec<Message>,
    /// Uplink LQ values the follower computed, in order.
    pub uplink_lq: Vec<u8>,
    /// Every smoothed uplink RSSI value the follower held, dBm.
    pub uplink_rssi_dbm: std::collections::BTreeSet<i16>,
    /// Messages sent down.
    pub sent: Vec<Message>,
    /// Every change of the follower's failsafe state: (virtual µs, in failsafe).
    pub failsafe_changes: Vec<(u64, bool)>,
    reader: MessageReader,
    updates: u32,
    next_telemetry_us: u64,
}

/// The flight side's follower hook.
pub struct FlightHooks {
    /// What it records.
    pub side: Shared<FlightSide>,
}

impl FollowerHooks for FlightHooks {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        let mut side = self.side.borrow_mut();
        let virtual_us = now_us - FLIGHT_EPOCH_US;
        if side.failsafe_changes.last().map(|c| c.1) != Some(follower.in_failsafe()) {
            side.failsafe_changes
                .push((virtual_us, follower.in_failsafe()));
        }
        if let Some(rssi) = follower.uplink_rssi_dbm() {
            side.uplink_rssi_dbm.insert(rssi);
        }
        if follower.updates() != side.updates {
            side.updates = follower.updates();
            side.outputs.push((virtual_us, *follower.output()));
        }
        let mut buf = [0u8; 64];
        loop {
            let n = follower.uplink_stream.read(&mut buf);
            if n == 0 {
                break;
            }
            for &b in &buf[..n] {
                if let Some(telemetry::messages::Decoded::Message(m)) = side.reader.push(b) {
                    side.received.push(m);
                }
            }
        }
        if now_us < side.next_telemetry_us {
            return;
        }
        side.next_telemetry_us = now_us + 100_000;
        let lq = follower.uplink_lq();
        side.uplink_lq.push(lq);
        let messages = [
            Message::Battery(flight_battery()),
            Message::Attitude(flight_attitude()),
            Message::FlightMode(FlightMode::AltitudeHold),
            Message::Gps(flight_gps()),
            Message::LinkStats(LinkStats {
                uplink_rssi_dbm: follower.uplink_rssi_dbm().unwrap_or(0) as i8,
                uplink_lq: lq,
                downlink_rssi_dbm: 0,
                downlink_lq: 0,
                rate_mode: follower.params().rate.code(),
                received: follower.counters().received,
                missed: follower.counters().missed,
                failsafes: 0,
            }),
        ];
        for message in messages {
            let mut frame = [0u8; 64];
            let n = encode_message(&message, &mut frame).unwrap().len();
            if follower.downlink_stream.free() >= n {
                follower.downlink_stream.write(&frame[..n]);
                side.sent.push(message);
            }
        }
    }
}

/// The module's master hook, as the firmware's link task has it.
pub struct ModuleHooks {
    /// The module core.
    pub app: Shared<ModuleApp>,
}

impl MasterHooks for ModuleHooks {
    fn on_slot(&mut self, now_us: u64, master: &mut Master) {
        let mut app = self.app.borrow_mut();
        app.on_master_slot(now_us, (now_us / 1_000) as u32, master);
    }
}

/// Module, flight side and the virtual air between them.
pub struct World<'a> {
    /// Virtual time.
    pub time: VirtualTime,
    /// Executor running every task.
    pub executor: Executor<'a>,
    /// The module core.
    pub app: Shared<ModuleApp>,
    /// The flight side.
    pub flight: Shared<FlightSide>,
}

impl World<'_> {
    /// Both ends, 200 m apart on a clean channel, the follower booting 123 ms after the
    /// master; a 10 Hz task does the module's periodic work. The follower declares failsafe
    /// after 250 ms of silence.
    pub fn new(settings: Settings) -> Self {
        Self::with_flight_failsafe(settings, 250_000)
    }

    /// As [`World::new`], with the follower's silence timeout (the flight firmware's is
    /// 500 ms).
    pub fn with_flight_failsafe(settings: Settings, failsafe_us: u64) -> Self {
        let time = VirtualTime::new();
        let medium = Medium::new(time.clone(), ChannelModel::default(), 7);
        let module_node = medium.add_node(Node::default());
        let flight_node = medium.add_node(Node {
            position_m: 200.0,
            ..Node::default()
        });
        let params = link_params(&settings).unwrap();
        let app = Rc::new(RefCell::new(
            App::new(settings, AirLink::new(), Handset::new(&settings), false).unwrap(),
        ));
        // As the firmware's link task: probe, then run what the core says.
        assert_eq!(app.borrow_mut().next_link_step(0, 0), LinkStep::Probe);
        app.borrow_mut().on_radio_present(true);
        assert_eq!(
            app.borrow_mut().next_link_step(0, 0),
            LinkStep::RunMaster(params)
        );
        let flight = Rc::new(RefCell::new(FlightSide::default()));
        let executor = Executor::new(time.clone());
        let mut hooks = ModuleHooks { app: app.clone() };
        let mut radio = MockRadio::new(medium.clone(), module_node);
        let mut clock = SimClock::new(time.clone(), MODULE_EPOCH_US, 0.0);
        let mut master = app.borrow().master(params);
        executor.spawn(async move {
            let _ = run_master(&mut radio, &mut clock, &mut master, &mut hooks).await;
        });
        let mut hooks = FlightHooks {
            side: flight.clone(),
        };
        let mut radio = MockRadio::new(medium, flight_node);
        let mut clock = SimClock::new(time.clone(), FLIGHT_EPOCH_US, 0.0);
        let flight_time = time.clone();
        executor.spawn(async move {
            flight_time.sleep_until(123_457).await;
            let mut follower = Follower::new(params, FailsafeValues::default(), failsafe_us);
            let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks).await;
        });
        let tick_app = app.clone();
        let tick_time = time.clone();
        executor.spawn(async move {
            let mut t = 0;
            loop {
                t += 100_000;
                tick_time.sleep_until(t).await;
                let mut app = tick_app.borrow_mut();
                app.on_ppm_tick((t + MODULE_EPOCH_US) as u32);
                app.on_tick();
            }
        });
        Self {
            time,
            executor,
            app,
            flight,
        }
    }

    /// Runs until virtual `end_us`.
    pub fn run_until(&mut self, end_us: u64) {
        self.executor.run_until_us(end_us);
    }
}

/// The module's firmware clock at virtual `t_us`.
pub fn module_now(t_us: u64) -> u64 {
    t_us + MODULE_EPOCH_US
}
