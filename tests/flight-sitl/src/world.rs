//! The simulated world, firmware in the loop: both ends' own applications on virtual
//! Si4432s. The module board (`module_end`: `module_core::App` and the module firmware's
//! task adapters) and the flight board (`flight_end`: `flight_app::app::FlightApp` and the
//! flight firmware's task adapters) each drive the real `radio-rfm22b` driver over
//! `si4432-sim`'s chips — SPI transactions at each board's bus clock, nIRQ latency — through
//! its RF medium; each end has its independent watchdog, and the flight end its settings
//! flash (`flash`), so a missed check-in is a reset and a power cycle reloads the stored
//! settings. The physics task steps the quad-sim 6-DoF quadrotor at the gyro rate and runs
//! the flight firmware's IMU adapter (`on_imu_sample`, motor commands to the quad with
//! `quad_sim::ground` contact), the baro and battery adapters every 20 ms and the alert
//! tone, and records a [`Sample`]. Everything runs in si4432-sim's deterministic executor
//! on one virtual clock: runs are exactly repeatable.
//!
//! Both boards boot at virtual time 0; the scenario's time starts [`WARMUP_S`] later, when
//! both boards have booted and the link is up (both ends start bound, as after a bind). During the warm-up the pilot's input is the one at time 0 (an arm switch
//! left on at power-up, the battery at its starting voltage). Boots during the warm-up
//! have negative times.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::time::Duration;

use flight_app::app::{FlightApp, ImuFault};
use flight_app::battery::BatteryLevel;
use flight_app::outputs::Command;
use flight_app::pipeline::{
    ChannelMap, ImuSample, LoopOutput, channel_for, from_settings, store_link, store_openlrs,
    throttle_channel,
};
use flight_app::settings::{Settings, handles};
use flight_app::supervisor::Sticks;
use flight_app::sysid::ekf::Identification;
use quad_sim::quad::{Quad, Truth};
use si4432_sim::{RadioConfig, SPI_CLOCK_F405_HZ, SPI_CLOCK_NRF52840_HZ, Simulation};
use telemetry::channels::{CHANNEL_CENTER, Channels, MAX_CHANNELS};
use telemetry::messages::{Message, SettingChange};
use telemetry::mock::SplitMix64;

use crate::clock::virtual_us;
use crate::flash::SettingsFlash;
use crate::flight_end::{FlightChip, flight_board, inject_radio};
use crate::module_end::{ModuleChip, module_board};
use crate::scenario::{End, ImuInjection, PilotInput, Scenario, Sight};
use si4432_sim::SimClock;

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
    /// The sticks the flight application held from the link this loop (what the loop flew
    /// on; the failsafe values in failsafe): a stick's move shows here when its uplink
    /// arrived at the flight controller.
    pub link_sticks: Sticks,
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
    /// The flight board's CPU was stalled by a flash operation this loop (code fetch from the
    /// single-bank flash stops, the flight loop's interrupt too): no IMU sample was handled,
    /// the motors kept their last commands. A gain design or a hung task holds only the
    /// thread-mode executor: the loop, in its interrupt executor, flies on.
    pub flight_busy: bool,
}

/// The run's records.
pub struct Sitl {
    /// One sample per loop.
    pub samples: Vec<Sample>,
    /// Loop period, s.
    pub ts_s: f64,
    /// Telemetry messages the module received, with the time (s).
    pub module_rx: Vec<(f64, Message)>,
    /// What the module sent to the handset on the JR line (each burst, with the time, s): the
    /// CRSF replies or the pushed S.Port / FrSky D frames, as the module's settings choose.
    pub handset_tx: Vec<(f64, Vec<u8>)>,
    /// The flight side's settings at the end (after changes from the module).
    pub settings: Settings,
    /// Independent-watchdog resets of each end.
    pub watchdog_resets: WatchdogResets,
    /// Every boot of either end, with the time (s) and why.
    pub boots: Vec<Boot>,
    /// The flight controller's log of each boot, as ULog files (the `log.profile` setting
    /// chooses what is in them; `off`: empty).
    pub flight_logs: Vec<Vec<u8>>,
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
    /// Its panic handler reset it (`PilotInput::flight_panic`).
    Panic,
    /// A watchdog or panic reset in the air, from which the flight was resumed
    /// (`flight_app::app::resume`).
    Resumed,
}

/// Virtual time before the scenario starts, s: both boards boot at 0, the flight side takes
/// 145 ms, then acquires the module (well under a second); the rest is margin, kept so the
/// scenario figures stay comparable.
pub const WARMUP_S: f64 = 4.0;
/// Distance between the module and the flight controller, m.
pub const DISTANCE_M: f64 = 100.0;
/// Attenuation of a cut link, dB.
pub const CUT_DB: f64 = 300.0;
/// The module's RFM22B crystal error, ppm.
pub const MODULE_CRYSTAL_PPM: f64 = 8.0;
/// The flight controller's RFM22B crystal error, ppm.
pub const FLIGHT_CRYSTAL_PPM: f64 = -6.0;

/// What the boards and the physics share.
pub(crate) struct WorldState {
    /// The pilot and the environment now.
    pub(crate) input: PilotInput,
    /// The flight application while the flight board runs, and its clock.
    pub(crate) flight: Option<(Rc<RefCell<FlightApp>>, SimClock)>,
    /// The flight settings when the flight board last stopped.
    pub(crate) flight_settings: Settings,
    /// The module's settings flash (kept across its resets).
    pub(crate) module_flash: crate::module_flash::ModuleFlash,
    /// A save the module core asked for, waiting for the module's settings task.
    pub(crate) module_save: Option<module_core::settings::Settings>,
    /// Until when (virtual ns) the module's CPU is halted by its NVMC (a settings save).
    pub(crate) module_busy_until_ns: u64,
    /// Messages the module relayed to the phone, with the scenario time (s).
    pub(crate) module_rx: Vec<(f64, Message)>,
    /// What the module sent on the JR line, with the scenario time (s).
    pub(crate) handset_tx: Vec<(f64, Vec<u8>)>,
    /// Whole CRSF frames the radio is to send in place of its next channel frames (a Lua
    /// tool's `crossfireTelemetryPush`), oldest first ([`World::radio_send`]).
    pub(crate) radio_frames: std::collections::VecDeque<Vec<u8>>,
    /// Setting changes the phone is still to send.
    pub(crate) uplink: Vec<SettingChange>,
    /// The HM-10's phone side as raw bytes, when a page is attached ([`World::attach_phone`]).
    pub(crate) phone: Option<PhonePipes>,
    /// The link key the phone knows (the pilot typed the flight side's phrase into it).
    pub(crate) phone_key: Option<telemetry::change_auth::ChangeKey>,
    pub(crate) watchdog_resets: WatchdogResets,
    pub(crate) boots: Vec<Boot>,
    /// Until when (virtual ns) the flight board's CPU is stalled by a flash operation: nothing
    /// runs, the loop's interrupt neither.
    pub(crate) flight_busy_until_ns: u64,
    /// Until when (virtual ns) the flight board's thread-mode executor is held by a blocking
    /// job (a gain design) or a hung task: the loop, in its interrupt executor, flies on.
    pub(crate) flight_thread_busy_until_ns: u64,
    /// The flight loop's side while the flight board runs (its IMU task owns it apart from
    /// the app, as the firmware's interrupt executor does).
    pub(crate) flight_loop: Option<flight_app::app::LoopSide>,
    /// The flight storage adapter stretches the watchdog around a save as the app's job
    /// asks (`false`: [`World::without_save_watchdog_stretch`]).
    pub(crate) save_stretch: bool,
    /// The flight board's LSI, Hz: what its IWDG counts.
    pub(crate) flight_lsi_hz: u32,
    /// The flight board's no-init RAM: the record a resume after a reset reads (kept across
    /// resets, lost with the power).
    pub(crate) flight_record: crate::flight_end::KeptRecord,
    /// The flight log of each boot (the last one growing).
    pub(crate) flight_logs: Vec<crate::flight_log::LogFile>,
    medium: si4432_sim::Medium,
}

impl WorldState {
    /// Scenario time now, s.
    pub(crate) fn scenario_s(&self) -> f64 {
        virtual_us(&self.medium) as f64 * 1e-6 - WARMUP_S
    }

    /// Virtual time now, ns.
    pub(crate) fn now_ns(&self) -> u64 {
        self.medium.now().as_nanos() as u64
    }

    /// The flight board's CPU is stalled by a flash operation.
    pub(crate) fn flight_busy(&self) -> bool {
        self.now_ns() < self.flight_busy_until_ns
    }

    /// The flight board's thread-mode executor is held (a gain design, a hung task, or the
    /// whole CPU by a flash operation).
    pub(crate) fn flight_thread_busy(&self) -> bool {
        self.flight_busy() || self.now_ns() < self.flight_thread_busy_until_ns
    }

    pub(crate) fn record_boot(&mut self, end: End, cause: BootCause, settings_error: bool) {
        let t_s = self.scenario_s();
        self.boots.push(Boot {
            t_s,
            end,
            cause,
            settings_error,
        });
    }
}

pub(crate) type Shared = Rc<RefCell<WorldState>>;

/// Bytes the HM-10 sent to the phone and the phone has not read yet; beyond this the oldest
/// are dropped (a stalled reader must not grow the world), as a BLE link would lose them.
pub const TO_PHONE_MAX: usize = 64 * 1024;
/// Bytes the phone wrote that the HM-10 task has not taken yet; beyond this a write is cut.
pub const FROM_PHONE_MAX: usize = 4 * 1024;

/// The HM-10's UART as a phone sees it: the relay's frames out, the phone's bytes in.
#[derive(Debug, Default)]
pub(crate) struct PhonePipes {
    pub(crate) to_phone: VecDeque<u8>,
    pub(crate) from_phone: VecDeque<u8>,
}

/// The transmitter's arm switch: channel 5 (AUX1), index 4 (`arm.channel 5` listens to it).
const ARM_SWITCH_CHANNEL: usize = 4;

/// The handset's channels for the pilot's sticks and switches (the PIL's handset plays the same).
pub fn transmitter(p: &PilotInput) -> Channels {
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

/// The module's settings for the scenario: the given ones (or the factory settings), bound
/// to the flight side as after a bind — an unbound module gets a bind ID drawn from the
/// seed, which the flight side then stores too — at the scenario's rate (`Scenario::rate`
/// decides both ends). A module given without a key flies the unauthenticated link (its
/// explicit setting; the flight side gets `link.unauthenticated`), as every world did before
/// the key agreement; one given a module key flies keyed, the flight side holding that
/// link's key as the bind hands it over.
pub fn module_settings(s: &Scenario) -> module_core::settings::Settings {
    let given = s.module_settings.unwrap_or_default();
    module_core::settings::Settings {
        plain: given.plain || given.link_key.is_none(),
        bind_id: if given.bind_id == 0 {
            // Never 0 (unbound): the low half is set.
            0x7A11_0000 | ((s.seed as u32) & 0xFFFF) | 1
        } else {
            given.bind_id
        },
        rate: s.rate,
        openlrs: module_core::settings::OpenLrsSettings {
            // An OpenLRSng link of its own, as after the module's first bind.
            hop_seed: if given.openlrs.hop_seed == 0 {
                0x0A15_0000 | ((s.seed as u32) & 0xFFFF) | 1
            } else {
                given.openlrs.hop_seed
            },
            ..given.openlrs
        },
        ..given
    }
}

/// The flight controller's side of the pairing: `settings` store `module`'s link as after a
/// bind (under model match the link of the lowest model the module records as bound) and,
/// with the OpenLRSng protocol, the bind data the module's OpenLRSng bind would send.
pub fn pair_flight_settings(settings: &mut Settings, module: &module_core::settings::Settings) {
    let bound_model = (module.model_match && module.bound_models != 0)
        .then(|| module.bound_models.trailing_zeros() as u8);
    if let Some(link) = module_core::air::link_params(module) {
        let link = bound_model.map_or(link, |m| link.for_model(m));
        let _ = store_link(settings, &link);
        // The key the bind handed over, or the unauthenticated link by the setting — unless
        // the scenario gave the flight side a key or the unauthenticated setting of its own
        // (a pair that does not match, on purpose).
        let own = settings.link_key().is_some() || settings.get(handles::LINK_UNAUTHENTICATED) == 1;
        if !own {
            settings.set_link_key(module.link_key.map(|k| k.for_link(link.bind_id)));
            let plain = u32::from(module.link_key.is_none());
            let _ = settings.apply(&[handles::LINK_UNAUTHENTICATED.to(plain)]);
        }
    }
    if let Ok(data) = module_core::settings::openlrs::bind_data(module) {
        let _ = store_openlrs(settings, &data);
    }
}

/// Runs `scenario` and returns the records.
///
/// # Panics
/// If the settings do not make a flyable configuration — a broken scenario, which the
/// test should show.
pub fn run(scenario: Scenario) -> Sitl {
    let mut world = World::new(scenario);
    world.run_to_end();
    world.finish()
}

/// What the pilot sees of the quad in `truth`.
fn sight(truth: &Truth) -> Sight {
    let state = &truth.state;
    Sight {
        altitude_m: -state.position_m[2],
        climb_mps: -state.velocity_mps[2],
        attitude_deg: truth.euler_deg,
        // `ground::contact` holds a landed frame at 0.
        on_ground: state.position_m[2] >= -1e-3,
        props_turning: state.motor.iter().any(|&m| m > 0.01),
    }
}

/// A world in the making: advanced in steps of virtual time ([`World::run_for`]), read while
/// it runs (samples, what the module relayed, the HM-10's phone side), and closed into its
/// records ([`World::finish`]). [`run`] is `new`, `run_to_end`, `finish`.
pub struct World {
    sim: Simulation,
    shared: Shared,
    samples: Rc<RefCell<Vec<Sample>>>,
    ts_s: f64,
    end: Duration,
}

impl World {
    /// The world of `scenario`, at virtual time 0 (both boards about to power up).
    ///
    /// # Panics
    /// If the settings do not make a flyable configuration — a broken scenario, which the
    /// test should show.
    #[allow(clippy::expect_used, clippy::too_many_lines)]
    pub fn new(mut scenario: Scenario) -> Self {
        let module = module_settings(&scenario);
        pair_flight_settings(&mut scenario.settings, &module);
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
            flight_flash,
            gps,
        } = scenario;
        let setup = from_settings(&settings).expect("settings make a flyable setup");
        let ts_s = f64::from(setup.loop_config.ts_s);
        let period_us = (ts_s * 1e6).round() as u64;
        let baro_every = ((f64::from(BARO_PERIOD_MS) * 1e-3 / ts_s).round() as u64).max(1);
        let battery_every = ((f64::from(BATTERY_PERIOD_MS) * 1e-3 / ts_s).round() as u64).max(1);

        let sim = Simulation::new(seed);
        let medium = sim.medium();
        medium.set_packet_loss(packet_loss);
        let placement = |x: f64, ppm: f64, spi_hz: u32| {
            let mut p = RadioConfig::at([x, 0.0, 0.0]);
            p.crystal_error_ppm = ppm;
            p.spi_clock_hz = spi_hz;
            p
        };
        let module_radio =
            medium.add_radio(placement(0.0, MODULE_CRYSTAL_PPM, SPI_CLOCK_NRF52840_HZ));
        let flight_radio =
            medium.add_radio(placement(DISTANCE_M, FLIGHT_CRYSTAL_PPM, SPI_CLOCK_F405_HZ));
        let (module_id, flight_id) = (module_radio.id, flight_radio.id);
        let (module_chip, flight_chip) = (module_radio.chip.clone(), flight_radio.chip.clone());
        let shared: Shared = Rc::new(RefCell::new(WorldState {
            input: PilotInput::default(),
            flight: None,
            flight_settings: settings.clone(),
            module_flash: crate::module_flash::ModuleFlash::new(&module),
            module_save: None,
            module_busy_until_ns: 0,
            module_rx: Vec::new(),
            handset_tx: Vec::new(),
            radio_frames: std::collections::VecDeque::new(),
            uplink: setting_changes,
            phone: None,
            phone_key: settings
                .link_key()
                .map(|k| telemetry::change_auth::ChangeKey::from_link_key(&k)),
            watchdog_resets: WatchdogResets::default(),
            flight_busy_until_ns: 0,
            flight_thread_busy_until_ns: 0,
            flight_loop: None,
            save_stretch: true,
            flight_logs: Vec::new(),
            flight_lsi_hz: flight_app::app::LSI_TYP_HZ,
            flight_record: crate::flight_end::KeptRecord::default(),
            boots: Vec::new(),
            medium: medium.clone(),
        }));
        let flash = SettingsFlash::new(&settings, flight_flash);
        sim.spawn(module_board(
            shared.clone(),
            medium.clone(),
            sim.time(),
            ModuleChip::new(module_radio, module.tx_power),
            seed,
        ));
        sim.spawn(flight_board(
            shared.clone(),
            medium.clone(),
            sim.time(),
            FlightChip::new(flight_radio),
            flash,
            link_failsafe_ms * 1000,
        ));
        let samples: Rc<RefCell<Vec<Sample>>> = Rc::new(RefCell::new(Vec::new()));
        let warmup_us = (WARMUP_S * 1e6) as u64;
        {
            let shared = shared.clone();
            let samples = samples.clone();
            let medium = medium.clone();
            let delay = sim.delay();
            let divider = setup.battery.voltage_divider;
            sim.spawn(async move {
                let mut quad = Quad::new(params, seed);
                quad_sim::ground::on_the_ground(&mut quad);
                let mut sensors = quad.sensors();
                let mut baro_noise = SplitMix64::new(seed ^ 0xBA40);
                let mut gps = gps.map(|g| crate::gps::GpsSim::new(g, seed));
                let mut level = BatteryLevel::Ok;
                let mut last_good = ImuSample {
                    gyro_radps: [0.0; 3],
                    accel_mps2: sensors.accel_mps2,
                    mag: None,
                };
                let mut last_out: Option<LoopOutput> = None;
                let mut before = PilotInput::default();
                let mut held_motors = [Command::Stopped; 4];
                let mut held_record = None;
                let mut held_tone = 0u16;
                let mut seen = Sight {
                    on_ground: true,
                    ..Sight::default()
                };
                let mut loops_since_boot: u64 = 0;
                let mut k: u64 = 0;
                loop {
                    k += 1;
                    let due_ns = k * period_us * 1000;
                    let now_ns = medium.now().as_nanos() as u64;
                    delay.sleep_ns(due_ns.saturating_sub(now_ns)).await;
                    let t_us = k * period_us;
                    let t_s = (t_us as f64 - warmup_us as f64) * 1e-6;
                    if t_s >= duration_s {
                        break;
                    }
                    // Before the scenario the world is as at its start (switches, battery).
                    let input = pilot.input(t_s.max(0.0), &seen);
                    if input.link_cut != before.link_cut {
                        let db = if input.link_cut { CUT_DB } else { 0.0 };
                        medium.set_attenuation(module_id, flight_id, db);
                    }
                    if input.flight_radio != before.flight_radio {
                        inject_radio(&flight_chip, before.flight_radio, input.flight_radio);
                    }
                    if input.module_radio != before.module_radio {
                        inject_radio(&module_chip, before.module_radio, input.module_radio);
                    }
                    before = input;
                    let (flight, busy, thread_busy) = {
                        let mut s = shared.borrow_mut();
                        s.input = input;
                        (s.flight.clone(), s.flight_busy(), s.flight_thread_busy())
                    };
                    let mut motors = [Command::Stopped; 4];
                    let mut record = None;
                    match &flight {
                        // The board is held by a flash operation or a gain design: no sample is
                        // taken, the motor timers keep the last commands.
                        Some(_) if busy => {
                            motors = held_motors;
                            record = held_record;
                        }
                        Some((app, clock)) => {
                            let mut app = app.borrow_mut();
                            let now_ms = clock.now_ms();
                            loops_since_boot += 1;
                            // The baro task (thread mode): MS5611 altitude at 50 Hz with
                            // 0.1 m (1σ) noise.
                            if !thread_busy && loops_since_boot.is_multiple_of(baro_every) {
                                let altitude =
                                    -quad.state().position_m[2] + baro_noise.normal(BARO_NOISE_M);
                                app.on_baro(now_ms, Some(altitude as f32));
                            }
                            // The GPS task: a NAV-PVT's bytes when the receiver has one
                            // (its DMA ring buffer keeps them while the task is held).
                            if let Some(g) = gps.as_mut().filter(|_| !thread_busy) {
                                let s = quad.state();
                                if let Some(bytes) =
                                    g.step(t_us / 1000, t_s, s.position_m, s.velocity_mps)
                                {
                                    app.on_gps_bytes(now_ms, &bytes);
                                }
                            }
                            let link = app.link_input();
                            // The IMU task (the loop's interrupt executor): a sample, or what
                            // the injected fault leaves of it, on the loop's side.
                            let imu = ImuSample {
                                gyro_radps: sensors.gyro_dps.map(|g| g * RAD_PER_DEG),
                                accel_mps2: sensors.accel_mps2,
                                mag: None,
                            };
                            let reading = match input.imu {
                                ImuInjection::Healthy => {
                                    last_good = imu;
                                    Ok(imu)
                                }
                                ImuInjection::Frozen => Ok(last_good),
                                ImuInjection::AllZero => Ok(ImuSample {
                                    gyro_radps: [0.0; 3],
                                    accel_mps2: [0.0; 3],
                                    mag: None,
                                }),
                                ImuInjection::Stalled => Err(ImuFault::Stalled),
                                ImuInjection::ReadError => Err(ImuFault::ReadError),
                            };
                            let step = {
                                let mut s = shared.borrow_mut();
                                let WorldState {
                                    flight_loop,
                                    flight_record,
                                    ..
                                } = &mut *s;
                                match flight_loop.as_mut() {
                                    Some(side) => {
                                        let step = crate::flight_end::imu_task_step(
                                            &mut app, side, now_ms, reading,
                                        );
                                        // It keeps the flight state and gains for a resume.
                                        flight_record.keep(&mut app, side, now_ms);
                                        step
                                    }
                                    None => flight_app::app::ImuStep {
                                        motors: [Command::Stopped; 4],
                                        reprobe: false,
                                    },
                                }
                            };
                            motors = step.motors;
                            // The battery task.
                            if !thread_busy && loops_since_boot.is_multiple_of(battery_every) {
                                app.on_battery(
                                    now_ms,
                                    battery_raw(input.battery_mv, divider),
                                    None,
                                );
                                level = app.battery().map_or(level, |b| b.level);
                            }
                            // The alert task (the tone holds while it is held).
                            let tone_hz = if thread_busy {
                                held_tone
                            } else {
                                app.on_alert_tick(now_ms)
                            };
                            held_tone = tone_hz;
                            // The logging task: what the app recorded, into this boot's file.
                            if let Some(log) = shared.borrow_mut().flight_logs.last_mut() {
                                log.drain(&mut app);
                            }
                            let identification = app.identification_finished();
                            if let Some(out) = app.last_output().copied() {
                                last_out = Some(out);
                            }
                            record = Some((
                                link.up,
                                link.sticks,
                                tone_hz,
                                identification,
                                step.reprobe,
                                app.imu_fault(),
                            ));
                        }
                        None => loops_since_boot = 0,
                    }
                    held_motors = motors;
                    held_record = record;
                    let cmds = motors.map(|m| match m {
                        Command::Throttle(x) => x,
                        Command::Stopped => 0.0,
                    });
                    let (s, truth) = quad.step(ts_s, &cmds);
                    let (truth, s) = quad_sim::ground::contact_level(&mut quad, truth, s);
                    sensors = s;
                    seen = sight(&truth);
                    // Nothing to record before the scenario or the loop's first output.
                    let Some(out) = last_out else { continue };
                    if t_s < 0.0 {
                        continue;
                    }
                    let flight_up = record.is_some();
                    let (link_up, link_sticks, tone_hz, identification, imu_reprobe, imu_fault) =
                        record.unwrap_or((false, Sticks::default(), 0, None, false, None));
                    samples.borrow_mut().push(Sample {
                        t_s,
                        pilot: input,
                        out,
                        link_up,
                        link_sticks,
                        altitude_m: -truth.state.position_m[2],
                        climb_mps: -truth.state.velocity_mps[2],
                        truth,
                        battery: level,
                        tone_hz,
                        identification,
                        motors,
                        imu_reprobe,
                        imu_fault,
                        flight_up,
                        flight_busy: busy && flight_up,
                    });
                }
            });
        }
        // An endless scenario runs until the caller stops stepping it.
        let end_us = warmup_us as f64 + duration_s * 1e6 + 2.0 * period_us as f64;
        let end = Duration::from_micros(if end_us < u64::MAX as f64 {
            end_us as u64
        } else {
            u64::MAX
        });
        Self {
            sim,
            shared,
            samples,
            ts_s,
            end,
        }
    }

    /// Types `bytes` at the running flight controller's USB console (`console`); one reply
    /// per finished line, none while the board is down.
    pub fn type_at_flight_console(&mut self, bytes: &[u8]) -> Vec<String> {
        let app = self
            .shared
            .borrow()
            .flight
            .as_ref()
            .map(|(app, _)| app.clone());
        app.map(|app| crate::console::type_into_console(&mut app.borrow_mut(), bytes))
            .unwrap_or_default()
    }

    /// The flight storage adapter no longer stretches the watchdog around a save (the app's
    /// `SaveJob::watchdog_ms` ignored): what the stretch is for, shown.
    pub fn without_save_watchdog_stretch(&mut self) {
        self.shared.borrow_mut().save_stretch = false;
    }

    /// The flight board's LSI runs at `hz` (the datasheet allows 17–47 kHz): its IWDG's
    /// timeout follows (`flight_app::app::IWDG`), from the next boot on.
    pub fn with_flight_lsi_hz(&mut self, hz: u32) {
        self.shared.borrow_mut().flight_lsi_hz = hz;
    }

    /// Runs `d` more of virtual time.
    pub fn run_for(&mut self, d: Duration) {
        self.sim.run_for(d);
    }

    /// Runs to the end of the scenario (its warm-up, duration and the last loops).
    pub fn run_to_end(&mut self) {
        self.run_for(self.end.saturating_sub(self.sim.now()));
    }

    /// Virtual time since power-up.
    pub fn now(&self) -> Duration {
        self.sim.now()
    }

    /// Scenario time now, s (negative during the warm-up).
    pub fn scenario_s(&self) -> f64 {
        self.shared.borrow().scenario_s()
    }

    /// The samples recorded since the last call (a long run's caller takes them as it goes).
    pub fn take_samples(&mut self) -> Vec<Sample> {
        std::mem::take(&mut *self.samples.borrow_mut())
    }

    /// The messages the module relayed to the phone since the last call, with the time (s).
    pub fn take_module_rx(&mut self) -> Vec<(f64, Message)> {
        std::mem::take(&mut self.shared.borrow_mut().module_rx)
    }

    /// The flight side's settings now: the running application's (changes from the link
    /// applied), or those it had when its board last stopped.
    pub fn flight_settings(&self) -> Settings {
        let s = self.shared.borrow();
        match &s.flight {
            Some((app, _)) => app.borrow().settings().clone(),
            None => s.flight_settings.clone(),
        }
    }

    /// Connects a phone to the module's HM-10: from now on the relay's frames are kept for
    /// [`World::phone_read`] (besides being decoded into the records) and
    /// [`World::phone_write`] bytes reach the module's HM-10 input, as over BLE.
    pub fn attach_phone(&mut self) {
        self.shared.borrow_mut().phone = Some(PhonePipes::default());
    }

    /// Bytes the phone writes to the HM-10 (cut at [`FROM_PHONE_MAX`] waiting; nothing
    /// without [`World::attach_phone`]).
    pub fn phone_write(&mut self, bytes: &[u8]) {
        if let Some(phone) = self.shared.borrow_mut().phone.as_mut() {
            let room = FROM_PHONE_MAX.saturating_sub(phone.from_phone.len());
            phone.from_phone.extend(bytes.iter().take(room));
        }
    }

    /// The simulated phone sends `change` now (the HM-10 task takes it at its next poll):
    /// signed with the flight side's phrase when the scenario gives one (re-signed once after
    /// the refusal that names the session), unsigned otherwise — as the scenario's
    /// `setting_changes` are.
    pub fn phone_change(&mut self, change: SettingChange) {
        self.shared.borrow_mut().uplink.push(change);
    }

    /// Everything the HM-10 sent to the phone since the last call.
    pub fn phone_read(&mut self) -> Vec<u8> {
        self.shared
            .borrow_mut()
            .phone
            .as_mut()
            .map(|p| p.to_phone.drain(..).collect())
            .unwrap_or_default()
    }

    /// The radio sends `frame` (a whole CRSF frame, address to CRC) in place of its next
    /// channel frame, as EdgeTX sends what a Lua script pushes (CRSF input only).
    pub fn radio_send(&mut self, frame: &[u8]) {
        self.shared
            .borrow_mut()
            .radio_frames
            .push_back(frame.to_vec());
    }

    /// What the module sent on the JR line since the last call, with the time (s).
    pub fn take_handset_tx(&mut self) -> Vec<(f64, Vec<u8>)> {
        std::mem::take(&mut self.shared.borrow_mut().handset_tx)
    }

    /// The records (the samples not yet taken).
    pub fn finish(self) -> Sitl {
        let settings = self.flight_settings();
        let Self {
            sim,
            shared,
            samples,
            ts_s,
            ..
        } = self;
        drop(sim);
        let samples = Rc::try_unwrap(samples)
            .map(RefCell::into_inner)
            .unwrap_or_default();
        let mut s = shared.borrow_mut();
        Sitl {
            samples,
            ts_s,
            module_rx: std::mem::take(&mut s.module_rx),
            handset_tx: std::mem::take(&mut s.handset_tx),
            settings,
            watchdog_resets: s.watchdog_resets,
            boots: std::mem::take(&mut s.boots),
            flight_logs: std::mem::take(&mut s.flight_logs)
                .into_iter()
                .map(crate::flight_log::LogFile::into_bytes)
                .collect(),
        }
    }
}
