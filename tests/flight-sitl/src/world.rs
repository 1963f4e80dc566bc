//! The simulated world: a module master and the flight-side follower on the mock air, and
//! the flight controller's own application (`flight_core::app::FlightApp`) driven by thin
//! simulated adapters making the firmware tasks' calls — the follower's hooks go to
//! `on_link_step`; at the gyro rate the quad's sensors go to `on_imu_sample` and its motor
//! commands to the quad (with `quad_sim::ground` contact); the baro every 20 ms to
//! `on_baro`, the battery ADC every 20 ms to `on_battery`, and `on_alert_tick` gives the
//! tone — and records a [`Sample`]. One executor, one virtual clock: runs are exactly
//! repeatable.

use std::cell::RefCell;
use std::rc::Rc;

use flight_core::app::{FlightApp, ImuFault};
use flight_core::battery::BatteryLevel;
use flight_core::outputs::Command;
use flight_core::pipeline::{ChannelMap, ImuSample, LoopOutput, channel_for, throttle_channel};
use flight_core::settings::Settings;
use flight_core::sysid::ekf::Identification;
use quad_sim::quad::{Quad, Truth};
use telemetry::channels::{CHANNEL_CENTER, ChannelFormat, Channels, FailsafeValues, MAX_CHANNELS};
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::{FollowerHooks, run_follower};
use telemetry::link::master::run_master;
use telemetry::link::{Band, LinkClock, LinkParams, RateMode};
use telemetry::messages::{Message, MessageReader};
use telemetry::mock::{
    ChannelModel, Executor, Medium, MockClock, MockRadio, Node, SplitMix64, VirtualTime,
};

use crate::module_end::{LinkState, MODULE_CLOCK_OFFSET_US, ModuleSide, Shared};
use crate::scenario::{ImuInjection, PilotInput, Scenario};

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
    /// The commands the motors got (the loop's, or the IMU fault policy's hold/stop).
    pub motors: [Command; 4],
    /// The app asked the IMU adapter to re-probe the sensor.
    pub imu_reprobe: bool,
    /// The standing IMU fault.
    pub imu_fault: Option<ImuFault>,
    /// The flight controller was running its application this loop (false while it is
    /// unpowered or booting; `out` is then the last output it gave, `motors` all stopped).
    pub flight_up: bool,
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
    /// Independent-watchdog resets of each end.
    pub watchdog_resets: WatchdogResets,
    /// Every boot of either end, with the time (s) and why.
    pub boots: Vec<Boot>,
}

/// Independent-watchdog resets counted per end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WatchdogResets {
    /// The flight controller.
    pub flight: u32,
    /// The module.
    pub module: u32,
}

/// One boot of one end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boot {
    /// Simulated time, s.
    pub t_s: f64,
    /// Which end.
    pub end: crate::scenario::End,
    /// Why it booted.
    pub cause: BootCause,
    /// What the settings load reported (flight end; `None` for the module).
    pub settings_error: bool,
}

/// Why an end booted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BootCause {
    /// Powered on (the first boot, or power back after `flight_powered` false).
    PowerOn,
    /// Its independent watchdog expired.
    Watchdog,
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

/// The flight link task's adapter: the follower's hooks go straight into the app.
struct AppHooks(Rc<RefCell<FlightApp>>);

impl FollowerHooks for AppHooks {
    fn on_step(&mut self, now_us: u64, follower: &mut Follower) {
        self.0.borrow_mut().on_link_step(now_us, follower);
    }
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
        rate: _,
        module_settings: _,
        flight_flash: _,
    } = scenario;
    // The application boots as the firmware's does: setup and gains solved before anything
    // can arm.
    let app = FlightApp::new(settings, 0).expect("settings make a setup");
    assert!(app.setup_error().is_none(), "settings make a flyable setup");
    let setup = *app.setup();
    let app = Rc::new(RefCell::new(app));
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
        let mut hooks = AppHooks(app.clone());
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
        let app = app.clone();
        ex.spawn(async move {
            let mut quad = Quad::new(params, seed);
            quad_sim::ground::on_the_ground(&mut quad);
            let mut sensors = quad.sensors();
            let mut baro_noise = SplitMix64::new(seed ^ 0xBA40);
            let mut level = BatteryLevel::Ok;
            let mut last_good = ImuSample {
                gyro_radps: [0.0; 3],
                accel_mps2: sensors.accel_mps2,
                mag: None,
            };
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
                shared.borrow_mut().tx = Some(transmitter(&input));
                let mut app = app.borrow_mut();
                // The baro task: MS5611 altitude at 50 Hz with 0.1 m (1σ) noise.
                if now_ms.is_multiple_of(BARO_PERIOD_MS) {
                    let altitude = -quad.state().position_m[2] + baro_noise.normal(BARO_NOISE_M);
                    app.on_baro(now_ms, Some(altitude as f32));
                }
                let link_up = app.link_input().up;
                // The IMU task: a sample, or what the injected fault leaves of it.
                let imu = ImuSample {
                    gyro_radps: sensors.gyro_dps.map(|g| g * RAD_PER_DEG),
                    accel_mps2: sensors.accel_mps2,
                    mag: None,
                };
                let step = match input.imu {
                    ImuInjection::Healthy => {
                        last_good = imu;
                        app.on_imu_sample(now_ms, &imu)
                    }
                    ImuInjection::Frozen => app.on_imu_sample(now_ms, &last_good),
                    ImuInjection::AllZero => app.on_imu_sample(
                        now_ms,
                        &ImuSample {
                            gyro_radps: [0.0; 3],
                            accel_mps2: [0.0; 3],
                            mag: None,
                        },
                    ),
                    ImuInjection::Stalled => app.on_imu_missing(now_ms, ImuFault::Stalled),
                    ImuInjection::ReadError => app.on_imu_missing(now_ms, ImuFault::ReadError),
                };
                let out = app.last_output().copied();
                let cmds = step.motors.map(|m| match m {
                    Command::Throttle(x) => x,
                    Command::Stopped => 0.0,
                });
                let (s, truth) = quad.step(ts_s, &cmds);
                let (truth, s) = quad_sim::ground::contact(&mut quad, truth, s);
                sensors = s;
                // The battery task.
                if now_ms.is_multiple_of(BATTERY_PERIOD_MS) {
                    app.on_battery(now_ms, battery_raw(input.battery_mv, divider), None);
                    level = app.battery().map_or(level, |b| b.level);
                }
                // The alert task.
                let tone_hz = app.on_alert_tick(now_ms);
                let identification = app.identification_finished();
                // Nothing to record before the loop's first output (an IMU dead at boot).
                let Some(out) = out else { continue };
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
                    motors: step.motors,
                    imu_reprobe: step.reprobe,
                    imu_fault: app.imu_fault(),
                    flight_up: true,
                });
            }
        });
    }
    ex.run_until((duration_s * 1e6) as u64 + 2 * period_us);
    drop(ex);
    let samples = Rc::try_unwrap(samples)
        .map(RefCell::into_inner)
        .unwrap_or_default();
    let module_rx = std::mem::take(&mut shared.borrow_mut().module_rx);
    let settings = app.borrow().settings().clone();
    Sitl {
        samples,
        ts_s,
        module_rx,
        settings,
        // Filled once the world models the watchdog and power (issue 12).
        watchdog_resets: WatchdogResets::default(),
        boots: Vec::new(),
    }
}
