//! What the pilot and the environment do over time: stick positions and switches on the
//! transmitter, link cuts, and the battery voltage at the ADC.

use flight_core::settings::Settings;
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
        }
    }
}

/// The pilot: a function of simulated time (s) to the input.
pub type Pilot = Box<dyn FnMut(f64) -> PilotInput>;

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
    pub pilot: Pilot,
    /// Setting changes the module sends up (in order, as soon as the stream has room).
    pub setting_changes: Vec<SettingChange>,
    /// Extra random packet loss on the air, 0…1 (both directions).
    pub packet_loss: f64,
}

/// The airframe the SITL flies by default: quad-sim's 250-class quad X with roll/pitch
/// ln β 10, yaw ln β 6.5, τ 30 ms, and the settings describing it — what identification and
/// autotune would have stored: the model, the analytic PID gains and the matched
/// frame-invariant LQG costs.
///
/// # Panics
/// If the autotune refuses the model (it does not for these numbers).
#[allow(clippy::expect_used)]
pub fn default_airframe() -> (QuadParams, Settings) {
    use flight_core::control::mixer::QUAD_X;
    use flight_core::settings::Value;
    use flight_core::sysid::autotune::{AutotuneSettings, analytic_pid, lqg_costs};
    let quad = QuadParams::quad_x(10.0, 6.5, 0.03, &QUAD_X);
    let mut s = Settings::default();
    let set = |s: &mut Settings, name: &str, v: f32| {
        // Names and ranges are fixed here; a failure is a test bug and shows as a bad flight.
        let _ = s.set(name, Value::F32(v));
    };
    set(&mut s, "lqg.ln_beta1.roll", 10.0);
    set(&mut s, "lqg.ln_beta1.pitch", 10.0);
    set(&mut s, "lqg.ln_beta1.yaw", 6.5);
    set(&mut s, "lqg.tau_s", 0.03);
    let tune = analytic_pid([10.0, 10.0, 6.5], 0.03, &AutotuneSettings::default())
        .expect("the autotune accepts the frame");
    for (axis, g) in ["roll", "pitch", "yaw"].iter().zip(tune.rate) {
        set(&mut s, &format!("pid.{axis}.kp"), g.kp);
        set(&mut s, &format!("pid.{axis}.ki"), g.ki);
        set(&mut s, &format!("pid.{axis}.kd"), g.kd);
    }
    set(&mut s, "pid.attitude.kp", tune.outer_kp);
    let costs = lqg_costs(&tune);
    set(&mut s, "lqg.q_attitude", costs.q1_angle as f32);
    set(&mut s, "lqg.q_rate", costs.q2_rate as f32);
    set(&mut s, "lqg.q_torque", costs.q4_torque as f32);
    (quad, s)
}
