//! The co-simulation: two emulated microcontrollers (the flight image on its board, the
//! module image on its board) stepped in lockstep quanta on one virtual clock with
//! si4432-sim's RF medium, quad-sim's 6-DoF physics, the handset and the pilot — flight-sitl's
//! scenario (pilot, faults, settings) flown with the images instead of the applications.
//!
//! **Time.** Virtual ns since both boards powered up (at 0). Each step of
//! [`QUANTUM_NS`] (5 µs) from `t` to `t + Q`: the physics is stepped to every IMU sample
//! instant and at least every millisecond up to `t + Q` (the samples, the baro's and the
//! battery's truth, the GPS), the handset's frames starting by then are queued edge by edge,
//! the medium is moved to `t + Q` (the radios' packets, with nIRQ's edges at the chips' own
//! times), every board's outbox goes to its SoC's input queues, then each MCU runs to
//! `t + Q`. Inputs known ahead (a data-ready, nIRQ falling, a PPM edge, a UART byte) carry
//! exact times. The timing error the quantum allows: an SPI access acts on a radio chip
//! already at `t + Q` (up to 5 µs early — below si4432-sim's own 5 µs nIRQ latency and 3 µs
//! SPI overhead); a level an MCU changes itself through a chip (a latched data-ready cleared
//! by its read, nIRQ released by a status read) reaches its own input up to 5 µs late; the
//! motors drive the physics with the pulse widths at the step's start (≤ 5 µs).
//!
//! **Records.** One [`flight_sitl::Sample`] per millisecond, as flight-sitl records them;
//! the flight controller's state in them is observed from outside ([`observe`]): motors,
//! buzzer, telemetry.

pub mod machine;
pub mod observe;
pub mod timing;

use flight_app::outputs::{Command, Protocol};
use flight_app::pipeline::{Attitude, LoopOutput, Source};
use flight_app::supervisor::{FlightMode, Sticks};
use flight_sitl::scenario::{ImuInjection, PilotInput, Piloting, Scenario, Sight};
use flight_sitl::world::{CUT_DB, DISTANCE_M, FLIGHT_CRYSTAL_PPM, MODULE_CRYSTAL_PPM, WARMUP_S};
use flight_sitl::{Boot, BootCause, End, Sample, Sitl, WatchdogResets};
use quad_sim::quad::{Quad, Sensors, Truth};
use si4432_sim::{ChipHandle, Medium, RadioConfig, RadioId, Simulation};
use sim_rng::SplitMix64;
use telemetry::messages::{Decoded, Message, MessageReader};

use crate::board::flight::{FlightBoard, FlightBoardKind};
use crate::board::module::ModuleBoard;
use crate::chips::handset;
use crate::chips::hm10::Hm10;
use crate::chips::motors::to_quad;
use crate::chips::ms5611::isa_pressure_pa;
use crate::chips::rfm22b::Rfm22b;
use crate::chips::ublox::{Generation, Ublox};
use machine::{Halt, Machine, MachineStats, deliver};

/// The lockstep quantum, ns.
pub const QUANTUM_NS: u64 = 5_000;
/// The record period and the physics' longest step, ns (1 kHz, flight-sitl's loop).
pub const RECORD_NS: u64 = 1_000_000;
/// The field's elevation above sea level, m (flight-sitl's GPS home).
pub const FIELD_MSL_M: f64 = 488.0;
/// Baro altitude noise, m (1σ, flight-sitl's).
pub const BARO_NOISE_M: f64 = 0.1;
/// The earth's field at the field, NED µT (central Europe: 48 µT at 63° inclination).
pub const EARTH_FIELD_NED_UT: [f64; 3] = [21.5, 0.5, 42.9];
/// The IMU's die temperature, °C.
pub const IMU_TEMP_C: f64 = 30.0;
/// The baro's die temperature, °C (above 20 °C: no second-order compensation).
pub const BARO_TEMP_C: f64 = 25.0;
/// The MPU-9250's and AK8963's oscillators, ppm off (a unit's own).
pub const IMU_PPM: (f64, f64) = (300.0, -500.0);

/// What the runner sets beyond the scenario.
#[derive(Debug, Clone)]
pub struct WorldConfig {
    /// The flight board.
    pub board: FlightBoardKind,
    /// The lockstep quantum, ns.
    pub quantum_ns: u64,
    /// The phone connects to the HM-10 this long after power-up, s (None: no phone).
    pub phone_at_s: Option<f64>,
    /// The PIN the pilot typed into the phone.
    pub phone_pin: Option<u32>,
    /// The GPS receiver's generation (Sparky2 with a GPS scenario).
    pub gps: Generation,
    /// The baro holds SDA low from this virtual time on (ns), needing this many SCL pulses.
    pub i2c_stuck: Option<(u64, u8)>,
    /// The change key the phone got by proving the binding phrase to the module (it signs
    /// setting changes).
    pub phone_key: Option<telemetry::change_auth::ChangeKey>,
    /// A USB host plugs into the flight board's console at this virtual time (ns) and asks
    /// `status` every [`CONSOLE_PERIOD_NS`] from then on (issue 29: the loop's jitter with
    /// the console busy).
    pub console_busy_from: Option<u64>,
}

/// How often the busy console's host asks `status`, ns.
pub const CONSOLE_PERIOD_NS: u64 = 10_000_000;
/// The host's first line this long after it plugged in (enumeration), ns.
const CONSOLE_ENUMERATION_NS: u64 = 500_000_000;

/// When the pilot's phone connects, s after power-up: once the module is up (its HM-10
/// script, which drops a phone that connects while it runs, ends ≈ 3.2 s after power-up
/// with the dist image), as a pilot opens the app after switching the radio on.
pub const PHONE_AT_S: f64 = 3.4;

impl Default for WorldConfig {
    fn default() -> Self {
        Self {
            board: FlightBoardKind::BrushedSparky,
            quantum_ns: QUANTUM_NS,
            phone_at_s: Some(PHONE_AT_S),
            phone_pin: None,
            gps: Generation::M8,
            i2c_stuck: None,
            phone_key: None,
            console_busy_from: None,
        }
    }
}

/// Both RFM22Bs on one medium, placed as flight-sitl places them.
pub struct Radios {
    /// The simulation that owns the medium's clock (kept alive with it).
    _sim: Simulation,
    /// The medium.
    pub medium: Medium,
    /// The flight side's radio (its board takes the handle).
    pub flight: Option<Rfm22b>,
    /// The module's radio.
    pub module: Option<Rfm22b>,
    flight_id: RadioId,
    module_id: RadioId,
    flight_chip: ChipHandle,
    module_chip: ChipHandle,
}

impl Radios {
    /// The medium for `seed` with both radios 100 m apart (flight-sitl's crystals and loss).
    pub fn new(seed: u64, packet_loss: f64) -> Self {
        let sim = Simulation::new(seed);
        let medium = sim.medium();
        medium.set_packet_loss(packet_loss);
        // The MCUs' SPI timing is their own: no bus cost in the chip model.
        let place = |x: f64, ppm: f64| {
            let mut c = RadioConfig::at([x, 0.0, 0.0]).with_instant_bus();
            c.crystal_error_ppm = ppm;
            c
        };
        let module = medium.add_radio(place(0.0, MODULE_CRYSTAL_PPM));
        let flight = medium.add_radio(place(DISTANCE_M, FLIGHT_CRYSTAL_PPM));
        Self {
            flight_id: flight.id,
            module_id: module.id,
            flight_chip: flight.chip.clone(),
            module_chip: module.chip.clone(),
            flight: Some(Rfm22b::new(flight)),
            module: Some(Rfm22b::new(module)),
            medium,
            _sim: sim,
        }
    }
}

/// The phone on the HM-10: it sends the scenario's setting changes, signed with the change key
/// (re-signed once after the refusal that names the flight side's session), as flight-sitl's
/// phone does; and sends a change again, freshly signed, when no answer (the echo or a
/// refusal) came within [`PHONE_ANSWER_NS`] — the link's records are not acknowledged, so an
/// uplink the flight radio missed loses the change, and a pilot whose app shows nothing
/// presses again.
struct Phone {
    signer: Option<telemetry::change_auth::Signer>,
    queue: Vec<telemetry::messages::SettingChange>,
    pending: Option<telemetry::messages::SettingChange>,
    next_ns: u64,
    sent_ns: u64,
}

/// The phone sends one change per this much time, ns, from [`PHONE_FIRST_NS`] after it
/// connected.
const PHONE_CHANGE_NS: u64 = 20_000_000;
/// The phone's first change this long after it connected, ns.
const PHONE_FIRST_NS: u64 = 200_000_000;
/// The phone sends a change again when nothing answered it for this long, ns (an answer
/// takes ≈ 0.1 s: the next uplink slot, the flight side's reply in the telemetry rotation).
pub const PHONE_ANSWER_NS: u64 = 500_000_000;

impl Phone {
    fn message(&mut self, change: telemetry::messages::SettingChange) -> Message {
        match self.signer.as_mut() {
            Some(s) => Message::SignedChange(s.sign(change)),
            None => Message::SettingChange(change),
        }
    }
}

fn encoded(message: &Message) -> Vec<u8> {
    let mut buf = [0u8; telemetry::messages::FRAMED_MAX_BYTES];
    telemetry::messages::encode_message(message, &mut buf)
        .map(<[u8]>::to_vec)
        .unwrap_or_default()
}

/// The physics and the truth at its last step.
struct Physics {
    quad: Quad,
    last_ns: u64,
    truth: Truth,
    sensors: Sensors,
    seen: Sight,
    baro_noise: SplitMix64,
}

/// Per record (1 ms), what the world knew then; the flight controller's state is rebuilt
/// at the end from these.
struct Record {
    t_ns: u64,
    pilot: PilotInput,
    truth: Truth,
    motors: [Command; 4],
    flight_up: bool,
}

/// The co-simulation of one scenario.
pub struct World<F: Machine<Board = FlightBoard>, M: Machine<Board = ModuleBoard>> {
    /// The flight MCU.
    pub flight: F,
    /// The module MCU.
    pub module: M,
    radios: Radios,
    physics: Physics,
    pilot: Box<dyn Piloting>,
    input: PilotInput,
    config: WorldConfig,
    now_ns: u64,
    end_ns: u64,
    next_record_ns: u64,
    next_frame_ns: u64,
    crsf: bool,
    last_good: Sensors,
    records: Vec<Record>,
    telemetry: Vec<(u64, Message)>,
    reader: MessageReader,
    boots: Vec<Boot>,
    /// The flight MCU's resets other than power-on (watchdog, the fault handler's), virtual
    /// ns at the record that first saw each.
    flight_resets: Vec<u64>,
    /// The flight MCU's reset and watchdog counts already accounted for, and whether the
    /// next reset is the power-on the world itself made.
    resets_seen: (u32, u32, bool),
    halts: Vec<(End, u64, Halt)>,
    stats_at_power_off: MachineStats,
    pilot_pin: Option<u32>,
    /// Data-ready to motor pulse.
    pub loop_timing: timing::LoopTiming,
    phone: Phone,
    /// The busy console: when the host types next (None: not plugged yet), and the bytes
    /// the firmware answered.
    console: (Option<u64>, usize),
}

/// The flight board for a scenario (radio from `radios`).
pub fn flight_board(
    config: &WorldConfig,
    radios: &mut Radios,
    protocol: Protocol,
    scenario: &Scenario,
) -> Option<FlightBoard> {
    let radio = radios.flight.take()?;
    let mut board = FlightBoard::new(config.board, radio, protocol, 0, IMU_PPM);
    if board.pins.gps_uart.is_some()
        && let Some(g) = scenario.gps.clone()
    {
        board.gps = Some(Ublox::new(config.gps, g, scenario.seed));
    }
    Some(board)
}

/// The module board (radio from `radios`) with a factory HM-10.
pub fn module_board(radios: &mut Radios) -> Option<ModuleBoard> {
    let radio = radios.module.take()?;
    Some(ModuleBoard::new(
        radio,
        Hm10::new(crate::chips::hm10::Config::default(), 0),
    ))
}

impl<F: Machine<Board = FlightBoard>, M: Machine<Board = ModuleBoard>> World<F, M> {
    /// The world of `scenario` with both machines built on their boards (from
    /// [`flight_board`] / [`module_board`] on the same `radios`), at virtual 0.
    pub fn new(
        scenario: Scenario,
        config: WorldConfig,
        radios: Radios,
        flight: F,
        module: M,
    ) -> Self {
        let module_settings = flight_sitl::world::module_settings(&scenario);
        let crsf = module_settings.input == module_core::settings::InputProtocol::Crsf;
        let mut params = scenario.quad.clone();
        // The images' own timing is the loop's latency here, not a whole sample.
        params.latency_samples = 0;
        let mut quad = Quad::new(params, scenario.seed);
        quad_sim::ground::on_the_ground(&mut quad);
        let sensors = quad.sensors();
        let truth = Truth {
            state: quad.state().clone(),
            euler_deg: [0.0; 3],
            rate_dps: [0.0; 3],
        };
        let warmup = (WARMUP_S * 1e9) as u64;
        Self {
            flight,
            module,
            radios,
            physics: Physics {
                quad,
                last_ns: 0,
                truth,
                sensors,
                seen: Sight {
                    on_ground: true,
                    ..Sight::default()
                },
                baro_noise: SplitMix64::new(scenario.seed ^ 0xBA40),
            },
            pilot: scenario.pilot,
            input: PilotInput::default(),
            end_ns: warmup + (scenario.duration_s.min(1e6) * 1e9) as u64,
            next_record_ns: RECORD_NS,
            next_frame_ns: 0,
            crsf,
            last_good: sensors,
            records: Vec::new(),
            telemetry: Vec::new(),
            reader: MessageReader::new(),
            boots: vec![
                Boot {
                    t_s: -WARMUP_S,
                    end: End::Module,
                    cause: BootCause::PowerOn,
                    settings_error: false,
                },
                Boot {
                    t_s: -WARMUP_S,
                    end: End::Flight,
                    cause: BootCause::PowerOn,
                    settings_error: false,
                },
            ],
            flight_resets: Vec::new(),
            resets_seen: (0, 0, false),
            halts: Vec::new(),
            stats_at_power_off: MachineStats::default(),
            pilot_pin: config.phone_pin,
            loop_timing: timing::LoopTiming::default(),
            console: (None, 0),
            phone: Phone {
                signer: config.phone_key.map(telemetry::change_auth::Signer::new),
                queue: scenario.setting_changes,
                pending: None,
                next_ns: 0,
                sent_ns: 0,
            },
            config,
            now_ns: 0,
        }
    }

    /// The radio medium (its trace: every frame on air and what the other radio made of it).
    pub fn medium(&self) -> &Medium {
        &self.radios.medium
    }

    /// Virtual time now, ns.
    pub fn now_ns(&self) -> u64 {
        self.now_ns
    }

    /// Scenario time of virtual `t_ns`, s.
    fn scenario_s(t_ns: u64) -> f64 {
        t_ns as f64 * 1e-9 - WARMUP_S
    }

    /// Runs to the scenario's end.
    pub fn run_to_end(&mut self) {
        while self.now_ns < self.end_ns {
            self.step();
        }
    }

    /// Runs until virtual `t_ns`.
    pub fn run_until(&mut self, t_ns: u64) {
        while self.now_ns < t_ns.min(self.end_ns) {
            self.step();
        }
    }

    /// One quantum.
    pub fn step(&mut self) {
        let t1 = self.now_ns + self.config.quantum_ns;
        self.physics_to(t1);
        self.handset_to(t1);
        self.module_chips(t1);
        self.console_to(t1);
        self.radios.medium.advance_to_ns(t1);
        self.flight.board().forward_radio();
        self.module.board().forward_radio();
        self.sync_bauds();
        let inputs = self.flight.board().outbox().take();
        deliver(&mut self.flight, inputs);
        let inputs = self.module.board().outbox().take();
        deliver(&mut self.module, inputs);
        if let Err(h) = self.flight.run_until(t1) {
            self.halts.push((End::Flight, t1, h));
        }
        if let Err(h) = self.module.run_until(t1) {
            self.halts.push((End::Module, t1, h));
        }
        let board = self.flight.board();
        let rises = board.take_int_rises();
        let pulses = board.take_motor_pulses();
        self.loop_timing.feed(&rises, &pulses);
        self.now_ns = t1;
    }

    fn sync_bauds(&mut self) {
        for uart in [1u8, 2] {
            if let Some(b) = self.flight.uart_baud(uart) {
                self.flight.board().set_uart_baud(uart, b);
            }
            if let Some(b) = self.module.uart_baud(uart) {
                self.module.board().set_uart_baud(uart, b);
            }
        }
    }

    /// The physics to `t1`: at each IMU sample instant and every record tick.
    fn physics_to(&mut self, t1: u64) {
        loop {
            let imu = self.flight.board().next_imu_sample_ns();
            let grid = self.next_record_ns;
            let next = imu.map_or(grid, |i| i.min(grid));
            if next > t1 {
                return;
            }
            self.physics_step(next);
            if imu == Some(next) {
                self.imu_sample();
            }
            if next == grid {
                self.record(next);
                self.next_record_ns += RECORD_NS;
            }
        }
    }

    fn physics_step(&mut self, t_ns: u64) {
        let dt = t_ns.saturating_sub(self.physics.last_ns);
        if dt == 0 {
            return;
        }
        let motors = self.flight.board().motor_commands(t_ns);
        let cmds = motors.map(to_quad);
        let p = &mut self.physics;
        let (s, truth) = p.quad.step(dt as f64 * 1e-9, &cmds);
        let (truth, s) = quad_sim::ground::contact_level(&mut p.quad, truth, s);
        p.sensors = s;
        p.seen = sight(&truth);
        p.truth = truth;
        p.last_ns = t_ns;
        let altitude = -p.truth.state.position_m[2];
        let noisy = FIELD_MSL_M + altitude + p.baro_noise.normal(BARO_NOISE_M);
        let battery_v = f64::from(self.input.battery_mv) * 1e-3;
        let current_a = cmds.iter().map(|c| f64::from(*c) * 2.0).sum();
        let state = p.truth.state.clone();
        let board = self.flight.board();
        board.environment(
            t_ns,
            isa_pressure_pa(noisy),
            BARO_TEMP_C,
            battery_v,
            current_a,
        );
        board.gps_tick(
            t_ns,
            Self::scenario_s(t_ns),
            state.position_m,
            state.velocity_mps,
        );
        if let Some((at, pulses)) = self.config.i2c_stuck
            && at <= t_ns
        {
            self.config.i2c_stuck = None;
            self.flight.board().baro.hold_sda_low(pulses);
        }
    }

    fn imu_sample(&mut self) {
        let s = self.physics.sensors;
        let q = self.physics.truth.state.attitude;
        let mag = rotate_to_body(q, EARTH_FIELD_NED_UT);
        let (sample, read_error) = match self.input.imu {
            ImuInjection::Healthy => {
                self.last_good = s;
                (Some(s), false)
            }
            ImuInjection::Frozen => (Some(self.last_good), false),
            ImuInjection::AllZero => (
                Some(Sensors {
                    gyro_dps: [0.0; 3],
                    accel_mps2: [0.0; 3],
                }),
                false,
            ),
            ImuInjection::Stalled => (None, false),
            ImuInjection::ReadError => (Some(s), true),
        };
        let board = self.flight.board();
        board.imu_read_error = read_error;
        match sample {
            Some(s) => board.imu_sample(
                s.accel_mps2.map(f64::from),
                s.gyro_dps.map(f64::from),
                mag,
                IMU_TEMP_C,
            ),
            None => board.mpu.skip_sample(),
        }
    }

    /// The pilot's input at `t_ns` and the environment it scripts.
    fn record(&mut self, t_ns: u64) {
        let t_s = Self::scenario_s(t_ns);
        let input = self.pilot.input(t_s.max(0.0), &self.physics.seen);
        let before = self.input;
        self.apply_input(&before, &input, t_ns);
        self.input = input;
        self.note_flight_reset(t_ns);
        let motors = self.flight.board().motor_commands(t_ns);
        self.records.push(Record {
            t_ns,
            pilot: input,
            truth: self.physics.truth.clone(),
            motors,
            flight_up: self.flight.powered(),
        });
    }

    /// A reset of the flight MCU since the last record that the world did not make (power
    /// on): a boot with its cause — the watchdog's, else the fault handler's (a resumed
    /// flight is told apart in [`World::finish`], from the `Health` telemetry).
    fn note_flight_reset(&mut self, t_ns: u64) {
        let stats = self.flight.stats();
        let (resets, watchdog, power_on) = self.resets_seen;
        if stats.resets > resets && !power_on {
            self.flight_resets.push(t_ns);
            self.boots.push(Boot {
                t_s: Self::scenario_s(t_ns),
                end: End::Flight,
                cause: if stats.watchdog_resets > watchdog {
                    BootCause::Watchdog
                } else {
                    BootCause::Panic
                },
                settings_error: false,
            });
        }
        let power_on = power_on && stats.resets == resets;
        self.resets_seen = (stats.resets, stats.watchdog_resets, power_on);
    }

    fn apply_input(&mut self, before: &PilotInput, input: &PilotInput, t_ns: u64) {
        if input.link_cut != before.link_cut {
            let db = if input.link_cut { CUT_DB } else { 0.0 };
            self.radios
                .medium
                .set_attenuation(self.radios.module_id, self.radios.flight_id, db);
        }
        if input.flight_radio != before.flight_radio {
            flight_sitl::flight_end::inject_radio(
                &self.radios.flight_chip,
                before.flight_radio,
                input.flight_radio,
            );
        }
        if input.module_radio != before.module_radio {
            flight_sitl::flight_end::inject_radio(
                &self.radios.module_chip,
                before.module_radio,
                input.module_radio,
            );
        }
        if input.flight_powered != before.flight_powered {
            if input.flight_powered {
                self.flight.set_powered(true, t_ns);
                self.flight.board().power_on(t_ns, IMU_PPM);
                self.resets_seen.2 = true;
                self.boots.push(Boot {
                    t_s: Self::scenario_s(t_ns),
                    end: End::Flight,
                    cause: BootCause::PowerOn,
                    settings_error: false,
                });
            } else {
                self.stats_at_power_off = self.flight.stats();
                self.flight.set_powered(false, t_ns);
            }
        }
    }

    /// The handset's frames that start by `t1`.
    fn handset_to(&mut self, t1: u64) {
        while self.next_frame_ns <= t1 {
            let t = self.next_frame_ns;
            let input = self.input;
            if self.crsf {
                self.next_frame_ns += handset::CRSF_PERIOD_NS;
                if input.handset_connected {
                    let frame = handset::crsf_channels(&handset::channels(&input));
                    self.module.board().crsf_from_handset(&frame, t);
                }
            } else {
                self.next_frame_ns += handset::PPM_FRAME_NS;
                if input.handset_connected {
                    let edges = handset::ppm_frame(t, &handset::channels(&input));
                    self.module.board().ppm(&edges);
                }
            }
        }
    }

    /// The busy console's host: plugs in at `console_busy_from`, then types `status` every
    /// [`CONSOLE_PERIOD_NS`] once it has enumerated.
    fn console_to(&mut self, t1: u64) {
        let Some(from) = self.config.console_busy_from.filter(|f| t1 >= *f) else {
            return;
        };
        match self.console.0 {
            None => {
                self.flight.usb_plug(true);
                self.console.0 = Some(from + CONSOLE_ENUMERATION_NS);
            }
            Some(next) if t1 >= next => {
                self.console.1 += self.flight.usb_type(b"status\n");
                self.console.0 = Some(next + CONSOLE_PERIOD_NS);
            }
            Some(_) => {}
        }
    }

    /// Bytes the busy console's host got back from the firmware.
    pub fn console_answered(&self) -> usize {
        self.console.1
    }

    fn module_chips(&mut self, t1: u64) {
        let board = self.module.board();
        if let Some(at) = self.config.phone_at_s.take() {
            board.hm10.phone_connects((at * 1e9) as u64, self.pilot_pin);
        }
        board.tick(t1);
        if board.hm10.connected() && !self.phone.queue.is_empty() {
            if self.phone.next_ns == 0 {
                self.phone.next_ns = t1 + PHONE_FIRST_NS;
            }
            if t1 >= self.phone.next_ns {
                self.phone.next_ns = t1 + PHONE_CHANGE_NS;
                let change = self.phone.queue.remove(0);
                self.phone.pending = Some(change);
                self.phone.sent_ns = t1;
                let m = self.phone.message(change);
                board.hm10.phone_write(&encoded(&m));
            }
        }
        if let Some(change) = self.phone.pending
            && board.hm10.connected()
            && t1 >= self.phone.sent_ns + PHONE_ANSWER_NS
        {
            self.phone.sent_ns = t1;
            let m = self.phone.message(change);
            board.hm10.phone_write(&encoded(&m));
        }
        let rx = board.hm10.take_phone_rx();
        for (t, chunk) in rx {
            for b in chunk {
                if let Some(Decoded::Message(m)) = self.reader.push(b) {
                    self.on_telemetry(t, m);
                }
            }
        }
    }

    fn on_telemetry(&mut self, t: u64, m: Message) {
        match (&m, self.phone.pending) {
            (Message::ChangeRefused(r), Some(change)) if r.id == change.id => {
                if self.phone.signer.as_mut().is_some_and(|s| s.on_refused(r)) {
                    self.phone.sent_ns = t;
                    let again = self.phone.message(change);
                    self.module.board().hm10.phone_write(&encoded(&again));
                } else {
                    // The refusal stands (a wrong phrase, armed, a bad value): shown, not retried.
                    self.phone.pending = None;
                }
            }
            (Message::SettingChange(echo), Some(change)) if echo.id == change.id => {
                self.phone.pending = None;
            }
            _ => {}
        }
        self.telemetry.push((t, m));
    }

    /// The flight MCU's figures (accumulated over power cycles).
    pub fn flight_stats(&self) -> MachineStats {
        self.flight.stats()
    }

    /// What stopped an MCU for good, if anything.
    pub fn halts(&self) -> &[(End, u64, Halt)] {
        &self.halts
    }

    /// Telemetry the phone received: (virtual ns, message).
    pub fn telemetry(&self) -> &[(u64, Message)] {
        &self.telemetry
    }

    /// A flight boot after a fault or watchdog reset whose `Health` telemetry says "flight
    /// resumed" (before the next boot) was a resumed flight.
    fn tell_resumed_boots(&mut self) {
        let resumed_at: Vec<f64> = self
            .telemetry
            .iter()
            .filter_map(|(t, m)| match m {
                Message::Health(h) if h.flags & telemetry::messages::Health::RESUMED != 0 => {
                    Some(Self::scenario_s(*t))
                }
                _ => None,
            })
            .collect();
        let flight_boots: Vec<f64> = self
            .boots
            .iter()
            .filter(|b| b.end == End::Flight)
            .map(|b| b.t_s)
            .collect();
        for b in self.boots.iter_mut().filter(|b| b.end == End::Flight) {
            if !matches!(b.cause, BootCause::Panic | BootCause::Watchdog) {
                continue;
            }
            let next = flight_boots
                .iter()
                .copied()
                .find(|t| *t > b.t_s)
                .unwrap_or(f64::INFINITY);
            if resumed_at.iter().any(|t| *t >= b.t_s && *t < next) {
                b.cause = BootCause::Resumed;
            }
        }
    }

    /// The records in flight-sitl's form, the flight controller's state observed from
    /// outside ([`observe`]).
    pub fn finish(&mut self) -> Sitl {
        let buzzer = self.flight.board().buzzer.edges.clone();
        let heard = observe::alerts_heard(&buzzer);
        let times: Vec<u64> = self.records.iter().map(|r| r.t_ns).collect();
        let armed: Vec<bool> = self
            .records
            .iter()
            .map(|r| r.flight_up && r.motors.iter().any(|m| *m != Command::Stopped))
            .collect();
        let gesture: Vec<bool> = self
            .records
            .iter()
            .map(|r| r.pilot.yaw > 0.9 && r.pilot.throttle < 0.05 || r.pilot.arm_switch < 0.0)
            .collect();
        let airborne: Vec<bool> = self
            .records
            .iter()
            .map(|r| -r.truth.state.position_m[2] > flight_sitl::runner::report::GROUND_M)
            .collect();
        let told: Vec<(u64, bool)> = self
            .telemetry
            .iter()
            .filter_map(|(t, m)| match m {
                Message::ArmState(a) => Some((*t, a.failsafe)),
                _ => None,
            })
            .collect();
        let observed = observe::rebuild(
            &times,
            &armed,
            &heard,
            &told,
            &gesture,
            &airborne,
            &self.flight_resets,
        );
        self.tell_resumed_boots();
        let mode = self
            .telemetry
            .iter()
            .rev()
            .find_map(|(_, m)| match m {
                Message::FlightMode(f) => Some(*f),
                _ => None,
            })
            .unwrap_or(FlightMode::Attitude);
        let warmup = (WARMUP_S * 1e9) as u64;
        let samples = self
            .records
            .iter()
            .zip(observed)
            .filter(|(r, _)| r.t_ns >= warmup)
            .map(|(r, o)| {
                let out = LoopOutput {
                    motors: r.motors,
                    decision: o.decision,
                    mode,
                    mode_changed: false,
                    armed: o.armed,
                    failsafe: o.failsafe,
                    attitude: Attitude::LEVEL,
                    estimator: Source::Complementary,
                };
                Sample {
                    t_s: Self::scenario_s(r.t_ns),
                    pilot: r.pilot,
                    out,
                    link_up: false,
                    link_sticks: Sticks::default(),
                    altitude_m: -r.truth.state.position_m[2],
                    climb_mps: -r.truth.state.velocity_mps[2],
                    truth: r.truth.clone(),
                    battery: o.battery,
                    tone_hz: 0,
                    identification: None,
                    motors: r.motors,
                    imu_reprobe: false,
                    imu_fault: None,
                    flight_up: r.flight_up,
                    flight_busy: false,
                }
            })
            .collect();
        let stats = self.flight.stats();
        Sitl {
            samples,
            ts_s: RECORD_NS as f64 * 1e-9,
            module_rx: self
                .telemetry
                .iter()
                .map(|(t, m)| (Self::scenario_s(*t), *m))
                .collect(),
            handset_tx: Vec::new(),
            settings: flight_app::settings::Settings::default(),
            watchdog_resets: WatchdogResets {
                flight: stats.watchdog_resets,
                module: self.module.stats().watchdog_resets,
            },
            boots: self.boots.clone(),
            // The images write no log stream yet (flight-fw has no logging task).
            flight_logs: Vec::new(),
        }
    }
}

/// The pilot's view of the quad (flight-sitl's).
fn sight(truth: &Truth) -> Sight {
    let state = &truth.state;
    Sight {
        altitude_m: -state.position_m[2],
        climb_mps: -state.velocity_mps[2],
        attitude_deg: truth.euler_deg,
        on_ground: state.position_m[2] >= -1e-3,
        props_turning: state.motor.iter().any(|&m| m > 0.01),
    }
}

/// `v` (NED) in body axes for the body → NED quaternion `q` (w, x, y, z).
pub fn rotate_to_body(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let [a, b, c] = v;
    // Rᵀ·v with R the body → NED rotation.
    [
        (1.0 - 2.0 * (y * y + z * z)) * a + 2.0 * (x * y + w * z) * b + 2.0 * (x * z - w * y) * c,
        2.0 * (x * y - w * z) * a + (1.0 - 2.0 * (x * x + z * z)) * b + 2.0 * (y * z + w * x) * c,
        2.0 * (x * z + w * y) * a + 2.0 * (y * z - w * x) * b + (1.0 - 2.0 * (x * x + y * y)) * c,
    ]
}

#[cfg(test)]
mod tests;
