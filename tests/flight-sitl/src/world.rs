//! The simulated world: a module master and the flight-side follower on the mock air, and
//! the flight task — at the gyro rate it reads the follower's channels, steps the
//! `FlightLoop` on the quad's sensors, applies the motor commands to the quad (with a ground
//! contact), runs the battery monitor at 50 Hz and the tone player every millisecond, and
//! records a [`Sample`]. One executor, one virtual clock: runs are exactly repeatable.

use std::cell::RefCell;
use std::rc::Rc;

use flight_core::alerts::TonePlayer;
use flight_core::battery::{BatteryLevel, BatteryMonitor};
use flight_core::outputs::Command;
use flight_core::pipeline::{
    ChannelMap, ClimbRate, Controllers, FlightLoop, ImuSample, LoopOutput, announce,
    announce_battery, channel_for, from_settings, throttle_channel,
};
use flight_core::report::{LinkSeen, Snapshot, sysid_messages};
use flight_core::settings::Settings;
use flight_core::sysid::ekf::Identification;
use quad_sim::quad::{GRAVITY_MPS2, Quad, QuadState, Truth};
use telemetry::channels::{CHANNEL_CENTER, ChannelFormat, Channels, FailsafeValues, MAX_CHANNELS};
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::run_follower;
use telemetry::link::master::run_master;
use telemetry::link::{Band, LinkClock, LinkParams, RateMode};
use telemetry::messages::{Message, MessageReader};
use telemetry::mock::{
    ChannelModel, Executor, Medium, MockClock, MockRadio, Node, SplitMix64, VirtualTime,
};

use crate::link_ends::{FlightSide, LinkState, MODULE_CLOCK_OFFSET_US, ModuleSide, Shared};
use crate::scenario::{PilotInput, Scenario};

const RAD_PER_DEG: f32 = core::f32::consts::PI / 180.0;
/// Baro sampling period, ms (the firmware's baro task rate).
const BARO_PERIOD_MS: u32 = 20;
/// Baro altitude noise, m (1σ; MS5611 at OSR 1024).
const BARO_NOISE_M: f64 = 0.1;
/// Battery sampling period, ms (the firmware's ADC task rate).
const BATTERY_PERIOD_MS: u32 = 20;

/// One loop's record.
#[derive(Debug, Clone)]
pub struct Sample {
    /// Simulated time, s.
    pub t_s: f64,
    /// What the pilot did.
    pub pilot: PilotInput,
    /// The loop's output.
    pub out: LoopOutput,
    /// The link delivered fresh channels this loop.
    pub link_up: bool,
    /// Ground truth (Euler angles deg, rates deg/s, state).
    pub truth: Truth,
    /// Altitude above ground, m.
    pub altitude_m: f64,
    /// Climb rate, m/s (up positive).
    pub climb_mps: f64,
    /// Battery level after the last reading.
    pub battery: BatteryLevel,
    /// The tone sounding (Hz, 0 = silence).
    pub tone_hz: u16,
    /// The identification that finished on this loop (system-identification mode left).
    pub identification: Option<Identification>,
}

/// The run's records.
pub struct Sitl {
    /// One sample per loop.
    pub samples: Vec<Sample>,
    /// Loop period, s.
    pub ts_s: f64,
    /// Telemetry messages the module received, with the time (s).
    pub module_rx: Vec<(f64, Message)>,
    /// The flight side's settings at the end (after changes from the module).
    pub settings: Settings,
}

/// The transmitter's arm switch: channel 5 (AUX1), index 4 (`arm.channel 5` listens to it).
const ARM_SWITCH_CHANNEL: usize = 4;

fn transmitter(p: &PilotInput) -> Channels {
    let mut ch = [CHANNEL_CENTER; MAX_CHANNELS];
    let map = ChannelMap::default();
    let mut set = |i: usize, v: u16| {
        if let Some(c) = ch.get_mut(i) {
            *c = v;
        }
    };
    set(map.roll, channel_for(p.roll));
    set(map.pitch, channel_for(p.pitch));
    set(map.throttle, throttle_channel(p.throttle));
    set(map.yaw, channel_for(p.yaw));
    set(map.mode, channel_for(p.mode_switch));
    set(ARM_SWITCH_CHANNEL, channel_for(p.arm_switch));
    ch
}

/// The ADC reading for a pack voltage through the configured divider (12 bit, 3.3 V).
fn battery_raw(pack_mv: f32, divider: f32) -> u16 {
    let v = pack_mv / divider / 3300.0 * 4095.0;
    v.clamp(0.0, 4095.0) as u16
}

/// Runs `scenario` and returns the records.
///
/// # Panics
/// If the settings do not make a flyable configuration or the gains do not solve — a
/// broken scenario, which the test should show.
#[allow(clippy::expect_used, clippy::too_many_lines)]
pub fn run(scenario: Scenario) -> Sitl {
    let Scenario {
        settings,
        quad: params,
        seed,
        duration_s,
        link_failsafe_ms,
        mut pilot,
        setting_changes,
        packet_loss,
    } = scenario;
    let setup = from_settings(&settings).expect("settings make a flyable setup");
    // Solve the gains before arming is possible, as the firmware does at boot.
    let controllers = Controllers::design(&setup.control).expect("gains solve");
    let ts_s = f64::from(setup.loop_config.ts_s);
    let period_us = (ts_s * 1e6).round() as u64;

    let time = VirtualTime::new();
    let channel = ChannelModel {
        loss: packet_loss,
        ..ChannelModel::default()
    };
    let medium = Medium::new(time.clone(), channel, seed);
    let module_node = medium.add_node(Node::default());
    let flight_node = medium.add_node(Node {
        position_m: 100.0,
        ..Node::default()
    });
    let params_link = LinkParams::new(
        0x5EED_0000 ^ (seed as u32),
        Band::Mhz433,
        RateMode::F250,
        ChannelFormat::Full16,
        4,
    );
    let shared: Shared = Rc::new(RefCell::new(LinkState {
        uplink: setting_changes,
        settings: settings.clone(),
        ..LinkState::default()
    }));
    let samples: Rc<RefCell<Vec<Sample>>> = Rc::new(RefCell::new(Vec::new()));

    let mut ex = Executor::new(time.clone());
    {
        let mut radio = MockRadio::new(medium.clone(), module_node);
        let mut clock = MockClock::new(time.clone(), MODULE_CLOCK_OFFSET_US);
        let mut hooks = ModuleSide {
            shared: shared.clone(),
            reader: MessageReader::new(),
        };
        ex.spawn(async move {
            let mut master = Master::new(params_link);
            let _ = run_master(&mut radio, &mut clock, &mut master, &mut hooks).await;
        });
    }
    {
        let mut radio = MockRadio::new(medium.clone(), flight_node);
        let mut clock = MockClock::new(time.clone(), 50_000_000);
        let mut hooks = FlightSide::new(shared.clone());
        ex.spawn(async move {
            // The flight controller boots a little after the module.
            let start = clock.now_us() + 77_777;
            clock.sleep_until_us(start).await;
            let mut follower = Follower::new(
                params_link,
                FailsafeValues::default(),
                link_failsafe_ms * 1000,
            );
            let _ = run_follower(&mut radio, &mut clock, &mut follower, &mut hooks).await;
        });
    }
    {
        let time = time.clone();
        let shared = shared.clone();
        let samples = samples.clone();
        let medium = medium.clone();
        let divider = setup.battery.voltage_divider;
        ex.spawn(async move {
            let mut quad = Quad::new(params, seed);
            let mut ground = quad.state().clone();
            ground.position_m = [0.0; 3];
            ground.motor.iter_mut().for_each(|m| *m = 0.0);
            quad.set_state(ground);
            let mut fl = FlightLoop::new(setup.loop_config, setup.mixer, Some(controllers));
            let mut battery = BatteryMonitor::new(setup.battery);
            let mut player = TonePlayer::new();
            let mut level = BatteryLevel::Ok;
            let mut last_battery = None;
            let map = setup.channels;
            let mut sensors = quad.sensors();
            let mut climb_filter = ClimbRate::new();
            let mut baro_climb = None;
            let mut baro_noise = SplitMix64::new(seed ^ 0xBA40);
            let mut next_us = period_us;
            let mut k: u64 = 0;
            while k as f64 * ts_s < duration_s {
                time.sleep_until(next_us).await;
                next_us += period_us;
                k += 1;
                let t_s = k as f64 * ts_s;
                let now_ms = (t_s * 1000.0).round() as u32;
                let input = pilot(t_s);
                medium.set_cut(module_node, flight_node, input.link_cut);
                let (rx, link_up) = {
                    let mut s = shared.borrow_mut();
                    s.tx = Some(transmitter(&input));
                    (s.rx, s.rx.is_some() && !s.failsafe)
                };
                let channels = rx.unwrap_or([CHANNEL_CENTER; MAX_CHANNELS]);
                let link = map.link_input(&channels, link_up);
                let imu = ImuSample {
                    gyro_radps: sensors.gyro_dps.map(|g| g * RAD_PER_DEG),
                    accel_mps2: sensors.accel_mps2,
                    mag: None,
                };
                // The baro task's path: MS5611 altitude at 50 Hz with 0.1 m (1σ) noise through
                // `ClimbRate`, held between readings.
                if now_ms.is_multiple_of(BARO_PERIOD_MS) {
                    let altitude = -quad.state().position_m[2] + baro_noise.normal(BARO_NOISE_M);
                    baro_climb = climb_filter.update(now_ms, altitude as f32);
                }
                let out = fl.step(now_ms, &imu, &link, baro_climb);
                let cmds = out.motors.map(|m| match m {
                    Command::Throttle(x) => x,
                    Command::Stopped => 0.0,
                });
                let (s, truth) = quad.step(ts_s, &cmds);
                sensors = s;
                // Ground contact: resting on the ground while thrust < weight, the frame does
                // not rotate and the accelerometer reads the ground's reaction.
                let on_ground = truth.state.position_m[2] >= 0.0;
                let thrust_n: f64 = truth
                    .state
                    .motor
                    .iter()
                    .map(|m| m * quad.params().max_thrust_n)
                    .sum();
                let truth = if on_ground && thrust_n < quad.params().mass_kg * GRAVITY_MPS2 {
                    let mut st: QuadState = truth.state.clone();
                    st.rate_rad_s = [0.0; 3];
                    st.velocity_mps = [0.0; 3];
                    quad.set_state(st);
                    sensors = quad.sensors();
                    // The model reads −thrust/m (+ noise) on z; the ground adds thrust/m − g.
                    let [ax, ay, az] = sensors.accel_mps2;
                    let reaction = thrust_n / quad.params().mass_kg - GRAVITY_MPS2;
                    sensors.accel_mps2 = [ax, ay, az + reaction as f32];
                    Truth {
                        rate_dps: [0.0; 3],
                        state: quad.state().clone(),
                        ..truth
                    }
                } else {
                    truth
                };
                announce(&mut player, &out);
                if now_ms.is_multiple_of(BATTERY_PERIOD_MS) {
                    let status =
                        battery.update(now_ms, battery_raw(input.battery_mv, divider), None);
                    level = status.level;
                    fl.set_battery_critical(level == BatteryLevel::Critical);
                    last_battery = Some(status);
                    if status.level_changed {
                        announce_battery(&mut player, level);
                    }
                }
                let tone_hz = player.tick(now_ms);
                let identification = fl.take_identification();
                if let Some(id) = &identification {
                    shared.borrow_mut().sysid.extend(sysid_messages(id));
                }
                shared.borrow_mut().snapshot = Some(Snapshot {
                    out,
                    battery: last_battery,
                    link: LinkSeen::default(),
                    arming_blockers: 0,
                    sysid: None,
                });
                samples.borrow_mut().push(Sample {
                    t_s,
                    pilot: input,
                    out,
                    link_up,
                    altitude_m: -truth.state.position_m[2],
                    climb_mps: -truth.state.velocity_mps[2],
                    truth,
                    battery: level,
                    tone_hz,
                    identification,
                });
            }
        });
    }
    ex.run_until((duration_s * 1e6) as u64 + 2 * period_us);
    drop(ex);
    let samples = Rc::try_unwrap(samples)
        .map(RefCell::into_inner)
        .unwrap_or_default();
    let (module_rx, settings) = {
        let mut s = shared.borrow_mut();
        (std::mem::take(&mut s.module_rx), s.settings.clone())
    };
    Sitl {
        samples,
        ts_s,
        module_rx,
        settings,
    }
}
