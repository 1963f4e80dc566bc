//! What the pilot and the environment do over time: stick positions and switches on the
//! transmitter, link cuts, and the battery voltage at the ADC.

use flight_app::settings::Settings;
use quad_sim::quad::QuadParams;
use telemetry::messages::SettingChange;

/// The pilot's transmitter and the world at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PilotInput {
    /// Throttle 0…1.
    pub throttle: f32,
    /// Roll −1…1.
    pub roll: f32,
    /// Pitch −1…1 (positive = nose up).
    pub pitch: f32,
    /// Yaw −1…1.
    pub yaw: f32,
    /// Mode switch −1 (low), 0 (mid), 1 (high).
    pub mode_switch: f32,
    /// The air path between module and flight controller is cut.
    pub link_cut: bool,
    /// Battery pack voltage, mV (what the divider feeds the ADC).
    pub battery_mv: f32,
    /// The arm switch on channel 5 (AUX1), −1 (off, factory window) … 1 (on).
    pub arm_switch: f32,
    /// What the IMU delivers (faults injected at the IMU adapter).
    pub imu: ImuInjection,
    /// The handset's PPM/CRSF input reaches the module (false: wire pulled, handset frozen —
    /// the module sees no more frames).
    pub handset_connected: bool,
    /// The flight controller is powered (false → true is a power-on boot: state lost,
    /// settings loaded from its simulated flash).
    pub flight_powered: bool,
    /// The flight side's RFM22B.
    pub flight_radio: RadioInjection,
    /// The module's RFM22B.
    pub module_radio: RadioInjection,
    /// The model selected on the radio (CRSF input: EdgeTX sends its model ID in a model-select
    /// command at start and whenever it changes); `None`: the radio sends none.
    pub radio_model: Option<u8>,
    /// The flight firmware panics (on the change to true): its handler stops the motors,
    /// records the fault and resets the board (`flight_app::app::resume`).
    pub flight_panic: bool,
    /// The flight firmware hangs (on the change to true): no task runs, the motor timers keep
    /// their last commands, the IWDG resets the board.
    pub flight_hang: bool,
}

/// A fault injected at one end's radio (chip and bus of the virtual Si4432).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RadioInjection {
    /// Working.
    #[default]
    Healthy,
    /// nIRQ reads low whatever the chip does (an unpowered module can read that way).
    IrqStuckLow,
    /// nIRQ never asserts.
    IrqStuckHigh,
    /// The chip is browned out: held in reset while this lasts, a power-on reset after it.
    BrownOut,
    /// Every SPI transfer fails while this lasts.
    SpiErrors,
}

/// What the flight controller's settings flash holds at the first boot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FlashInjection {
    /// The scenario's settings, cleanly stored.
    #[default]
    Stored,
    /// The scenario's settings stored, then corrupted from this seed: a few bit flips in
    /// the written bytes and both sectors' state markers overwritten (a torn sector close),
    /// which sequential-storage reads as a corrupted map.
    Corrupted(u64),
    /// Erased (a new board).
    Erased,
    /// The scenario's settings stored, then the map filled with earlier saves until the next
    /// save of a changed parameter must erase a sector (sequential-storage erases when it
    /// runs out of room): that save stalls the F405 for a sector erase.
    NearlyFull,
}

/// The end of the link a figure belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// The flight controller.
    Flight,
    /// The JR-bay module.
    Module,
}

/// An IMU fault injected at the simulated IMU task.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ImuInjection {
    /// Real samples.
    #[default]
    Healthy,
    /// No data-ready edge.
    Stalled,
    /// Bus reads fail.
    ReadError,
    /// The last good sample, bit for bit, again and again.
    Frozen,
    /// All six axes read zero.
    AllZero,
}

impl Default for PilotInput {
    /// Sticks centred, throttle low, mode switch low, link up, a charged 1S pack (the
    /// BrushedSparky's 10 k / 10 k divider reads up to 6.6 V).
    fn default() -> Self {
        Self {
            throttle: 0.0,
            roll: 0.0,
            pitch: 0.0,
            yaw: 0.0,
            mode_switch: -1.0,
            link_cut: false,
            battery_mv: 4_150.0,
            arm_switch: -1.0,
            imu: ImuInjection::Healthy,
            handset_connected: true,
            flight_powered: true,
            flight_radio: RadioInjection::Healthy,
            module_radio: RadioInjection::Healthy,
            radio_model: None,
            flight_panic: false,
            flight_hang: false,
        }
    }
}

/// What the pilot sees of the aircraft at one instant: the truth, as a person at the
/// transmitter looking at the quad (not anything the flight controller estimates).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sight {
    /// Height above the ground, m.
    pub altitude_m: f64,
    /// Climb rate, m/s (up positive).
    pub climb_mps: f64,
    /// Roll, pitch, yaw, deg.
    pub attitude_deg: [f64; 3],
    /// Sitting on the ground.
    pub on_ground: bool,
    /// Any propeller turning.
    pub props_turning: bool,
}

/// The person at the transmitter: the sticks and switches (and the environment the
/// scenario scripts with them) at scenario time `t_s`, having seen the aircraft as `sight`
/// (its state after the previous physics step). Any `FnMut(f64) -> PilotInput` (a
/// [`Pilot`]) flies by the clock alone.
pub trait Piloting {
    /// The input at `t_s`.
    fn input(&mut self, t_s: f64, sight: &Sight) -> PilotInput;
}

/// A pilot flying by the clock alone: a function of scenario time (s) to the input.
pub type Pilot = Box<dyn FnMut(f64) -> PilotInput>;

impl<F: FnMut(f64) -> PilotInput + ?Sized> Piloting for Box<F> {
    fn input(&mut self, t_s: f64, _sight: &Sight) -> PilotInput {
        self(t_s)
    }
}

/// One simulated flight.
pub struct Scenario {
    /// Flight-controller settings (as the console would set them).
    pub settings: Settings,
    /// The airframe.
    pub quad: QuadParams,
    /// Sensor noise seed.
    pub seed: u64,
    /// Length, s.
    pub duration_s: f64,
    /// Link failsafe time of the follower, ms.
    pub link_failsafe_ms: u64,
    /// The pilot.
    pub pilot: Box<dyn Piloting>,
    /// Setting changes the module sends up (in order, as soon as the stream has room).
    pub setting_changes: Vec<SettingChange>,
    /// Extra random packet loss on the air, 0…1 (both directions).
    pub packet_loss: f64,
    /// The link's rate mode (both ends bound at it).
    pub rate: telemetry::link::RateMode,
    /// The module's settings (`None`: factory). The world binds them to the flight side (an
    /// unbound module gets the flight controller's compiled-in link ID) and sets their rate
    /// from [`Scenario::rate`].
    pub module_settings: Option<module_core::settings::Settings>,
    /// What the flight controller's settings flash holds at the first boot.
    pub flight_flash: FlashInjection,
    /// A GPS receiver on the flight controller's GPS port (`None`: no receiver).
    pub gps: Option<crate::gps::GpsConfig>,
}

impl Scenario {
    /// A scenario with the defaults: seed 7, link failsafe 500 ms, no setting changes, no
    /// extra loss, F250, the module's factory settings bound to the flight side, settings
    /// cleanly stored.
    pub fn new(settings: Settings, quad: QuadParams, duration_s: f64, pilot: Pilot) -> Self {
        Self::flown_by(settings, quad, duration_s, pilot)
    }

    /// [`Scenario::new`] with a pilot that looks at the aircraft.
    pub fn flown_by(
        settings: Settings,
        quad: QuadParams,
        duration_s: f64,
        pilot: impl Piloting + 'static,
    ) -> Self {
        Self {
            settings,
            quad,
            seed: 7,
            duration_s,
            link_failsafe_ms: 500,
            pilot: Box::new(pilot),
            setting_changes: Vec::new(),
            packet_loss: 0.0,
            rate: telemetry::link::RateMode::F250,
            module_settings: None,
            flight_flash: FlashInjection::Stored,
            gps: None,
        }
    }
}

/// The airframe the SITL flies by default: quad-sim's 250-class quad X with roll/pitch
/// ln β 10, yaw ln β 6.5, τ 30 ms, and the settings describing it — what identification and
/// autotune would have stored: the model, the analytic PID gains and the matched
/// frame-invariant LQG costs.
///
/// # Panics
/// If the autotune refuses the model, or the table a value (neither happens for these
/// numbers).
#[allow(clippy::expect_used)]
pub fn default_airframe() -> (QuadParams, Settings) {
    use flight_app::control::mixer::QUAD_X;
    use flight_app::settings::handles::*;
    use flight_app::sysid::autotune::{AutotuneSettings, analytic_pid, lqg_costs};
    let quad = QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X);
    let mut s = Settings::default();
    let tune = analytic_pid([10.0, 10.0, 6.5], 0.03, &AutotuneSettings::default())
        .expect("the autotune accepts the frame");
    let costs = lqg_costs(&tune);
    let [roll, pitch, yaw] = LQG_LN_BETA1;
    let mut changes = vec![
        roll.to(10.0),
        pitch.to(10.0),
        yaw.to(6.5),
        LQG_TAU_S.to(0.03),
        PID_ATTITUDE_KP.to(tune.outer_kp),
        LQG_Q_ATTITUDE.to(costs.q1_angle as f32),
        LQG_Q_RATE.to(costs.q2_rate as f32),
        LQG_Q_TORQUE.to(costs.q4_torque as f32),
    ];
    for ([kp, ki, kd], g) in PID_GAINS.into_iter().zip(tune.rate) {
        changes.extend([kp.to(g.kp), ki.to(g.ki), kd.to(g.kd)]);
    }
    s.apply(&changes)
        .expect("the autotuned airframe is within the table's ranges");
    (quad, s)
}
