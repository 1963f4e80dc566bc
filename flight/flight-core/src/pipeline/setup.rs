//! From the parameter table to everything the flight loop and the firmware need: the loop
//! configuration, the controller design inputs, the output protocol, the mixer and the
//! battery thresholds. Pure, so every mapping is host-tested; the firmware calls it at boot
//! and after a setting changes (while disarmed), then solves the gains with
//! [`Controllers::design`](super::Controllers::design) before arming is allowed.

use super::channels::ChannelMap;
use super::controllers::ControlParams;
use super::estimator::EstimatorMode;
use super::flight_loop::LoopConfig;
use super::sticks::StickShaping;
use crate::battery::BatteryConfig;
use crate::control::design::{FrameInvariantCosts, KfNoise};
use crate::control::mixer::{Mixer, QUAD_PLUS, QUAD_X, ThrustCurve};
use crate::control::pid::PidGains;
use crate::estimation::complementary;
use crate::model::{AxisModel, ModelError};
use crate::outputs::Protocol;
use crate::settings::{Handle, Settings, handles};
use crate::supervisor::{FlightMode, Settings as SupervisorSettings};

/// Everything derived from the settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightSetup {
    /// The loop's fixed configuration.
    pub loop_config: LoopConfig,
    /// What the controller design needs.
    pub control: ControlParams,
    /// How the motor outputs are driven.
    pub protocol: Protocol,
    /// Frame geometry and thrust curve.
    pub mixer: Mixer<4>,
    /// Battery sensing and thresholds.
    pub battery: BatteryConfig,
    /// Gyro loop rate, Hz.
    pub loop_rate_hz: u32,
    /// Which link channel carries what, with the arm switch if one is set.
    pub channels: ChannelMap,
}

/// Why the settings do not make a flyable configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SetupError {
    /// The frame has more than four motors; the loop drives four.
    FrameNotSupported,
    /// A model parameter is unusable.
    Model(ModelError),
    /// A choice index no table entry names (a corrupted store).
    BadChoice,
    /// The warning threshold is below the critical one.
    BatteryThresholds,
    /// The arm switch is set to a stick's or the mode switch's channel.
    ArmChannelInUse,
    /// The arm switch's window is empty (`arm.min_us` not below `arm.max_us`).
    ArmWindow,
}

impl core::fmt::Display for SetupError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SetupError::FrameNotSupported => f.write_str("frame needs more than four motors"),
            SetupError::Model(e) => write!(f, "model: {e}"),
            SetupError::BadChoice => f.write_str("setting holds an unknown choice"),
            SetupError::BatteryThresholds => f.write_str("battery warning below critical"),
            SetupError::ArmChannelInUse => f.write_str("arm channel is a stick or the mode switch"),
            SetupError::ArmWindow => f.write_str("arm.min_us must be below arm.max_us"),
        }
    }
}

impl core::error::Error for SetupError {}

impl From<ModelError> for SetupError {
    fn from(e: ModelError) -> Self {
        SetupError::Model(e)
    }
}

/// The `settings::MODES` choice index as a flight mode: the index is the mode's stable id.
fn mode(index: u32) -> Result<FlightMode, SetupError> {
    u8::try_from(index)
        .ok()
        .and_then(FlightMode::from_id)
        .ok_or(SetupError::BadChoice)
}

/// One axis's rate PID gains (`handles::PID_GAINS` row: kp, ki, kd).
fn pid(s: &Settings, gains: [Handle<f32>; 3]) -> PidGains {
    let [kp, ki, kd] = gains.map(|g| s.get(g));
    // The derivative filter: a 2 ms time constant (≈ 80 Hz), as the flight-core defaults.
    PidGains::new(kp, ki, kd, 0.002)
}

/// Builds the whole configuration from `s`.
pub fn from_settings(s: &Settings) -> Result<FlightSetup, SetupError> {
    let loop_rate_hz = match s.get(handles::LOOP_RATE_HZ) {
        0 => 500,
        1 => 1000,
        _ => return Err(SetupError::BadChoice),
    };
    let ts_s = 1.0 / loop_rate_hz as f32;
    let shaping = StickShaping {
        max_rate_dps: s.get(handles::RATE_MAX_DPS),
        max_angle_deg: s.get(handles::ATTITUDE_MAX_DEG),
        ..StickShaping::default()
    };
    let supervisor = SupervisorSettings {
        idle_disarm_ms: s.get(handles::ARM_IDLE_DISARM_MS),
        arm_on_critical_battery: s.get(handles::ARM_CRITICAL_BATTERY) == 1,
        failsafe_descent_mps: s.get(handles::FAILSAFE_DESCENT_MPS),
        ..SupervisorSettings::default()
    };
    let modes = [
        mode(s.get(handles::MODE_SWITCH_LOW))?,
        mode(s.get(handles::MODE_SWITCH_MID))?,
        mode(s.get(handles::MODE_SWITCH_HIGH))?,
    ];
    let loop_config = LoopConfig {
        ts_s,
        shaping,
        idle: s.get(handles::OUTPUT_IDLE),
        supervisor,
        modes,
        attitude_uses_lqg: true,
        attitude_filter: complementary::Config {
            earth_field_ned: crate::estimation::align::field_for_declination(
                s.get(handles::MAG_DECLINATION_DEG).to_radians(),
            ),
            ..complementary::Config::default()
        },
        // Ground kp 1 rad/s per rad → 0.05 in flight (a 20 s time constant).
        armed_accel_divider: 20,
        estimator: match s.get(handles::INS_MODE) {
            0 => EstimatorMode::Complementary,
            1 => EstimatorMode::Ins,
            2 => EstimatorMode::InsIndoor,
            _ => return Err(SetupError::BadChoice),
        },
    };
    let tau_s = s.get(handles::LQG_TAU_S);
    // The yaw entry is the yaw axis' authority (β of the drag torque, `control/LQG.md` §1); the
    // lag-free β2 term is left to identification.
    let [roll, pitch, yaw] = handles::LQG_LN_BETA1;
    let models = [
        AxisModel::new(s.get(roll), tau_s)?,
        AxisModel::new(s.get(pitch), tau_s)?,
        AxisModel::new(s.get(yaw), tau_s)?,
    ];
    // The stored costs are frame-invariant (q1 angle, q2 rate, q4 torque; design.rs
    // `FrameInvariantCosts`): what autotune's `lqg_costs` produces, and they stay right when
    // identification changes β. Each axis gets them scaled by its own β1. One set serves
    // both solves; the rate solve ignores the angle cost (`control/LQG.md` §3).
    let invariant = FrameInvariantCosts {
        q1_angle: f64::from(s.get(handles::LQG_Q_ATTITUDE)),
        q2_rate: f64::from(s.get(handles::LQG_Q_RATE)),
        q4_torque: f64::from(s.get(handles::LQG_Q_TORQUE)),
    };
    let costs = models.map(|m| invariant.for_beta(m.beta1()));
    let control = ControlParams {
        ts_s,
        models,
        rate_costs: costs,
        attitude_costs: costs,
        noise: KfNoise::default(),
        pid_rate: handles::PID_GAINS.map(|axis| pid(s, axis)),
        attitude_kp: s.get(handles::PID_ATTITUDE_KP),
        attitude_max_rate_dps: shaping.max_rate_dps,
        // Synchronous outputs: the command reaches the motors one sample after the gyro read.
        output_delay_samples: 1,
    };
    let protocol = match s.get(handles::OUTPUT_PROTOCOL) {
        0 => Protocol::Brushed {
            frequency_hz: s.get(handles::OUTPUT_RATE_HZ),
        },
        1 => Protocol::Pwm {
            rate_hz: s.get(handles::OUTPUT_RATE_HZ),
            min_us: u16::try_from(s.get(handles::OUTPUT_MIN_US))
                .map_err(|_| SetupError::BadChoice)?,
            max_us: u16::try_from(s.get(handles::OUTPUT_MAX_US))
                .map_err(|_| SetupError::BadChoice)?,
        },
        2 => Protocol::OneShot125,
        _ => return Err(SetupError::BadChoice),
    };
    let expo = s.get(handles::MIXER_THRUST_EXPO);
    let curve = if expo > 0.0 {
        ThrustCurve::Quadratic { k: expo }
    } else {
        ThrustCurve::Linear
    };
    let mixer = match s.get(handles::MIXER_FRAME) {
        0 => Mixer::new(QUAD_X, curve),
        1 => Mixer::new(QUAD_PLUS, curve),
        2 => return Err(SetupError::FrameNotSupported),
        _ => return Err(SetupError::BadChoice),
    };
    let warning = u16::try_from(s.get(handles::BATTERY_CELL_WARNING_MV)).unwrap_or(u16::MAX);
    let critical = u16::try_from(s.get(handles::BATTERY_CELL_CRITICAL_MV)).unwrap_or(u16::MAX);
    if warning < critical {
        return Err(SetupError::BatteryThresholds);
    }
    let cells = u8::try_from(s.get(handles::BATTERY_CELLS)).unwrap_or(0);
    let sense = s.get(handles::BATTERY_CURRENT_MV_PER_A);
    let battery = BatteryConfig {
        voltage_divider: s.get(handles::BATTERY_DIVIDER),
        current_mv_per_amp: (sense > 0.0).then_some(sense),
        cells: (cells > 0).then_some(cells),
        cell_warning_mv: warning,
        cell_critical_mv: critical,
        ..BatteryConfig::brushed_sparky()
    };
    let channels = ChannelMap::from_settings(s)?;
    Ok(FlightSetup {
        channels,
        loop_config,
        control,
        protocol,
        mixer,
        battery,
        loop_rate_hz,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::Controllers;
    use crate::settings::Value;

    #[test]
    fn defaults_map_to_the_documented_configuration() {
        let setup = from_settings(&Settings::default()).unwrap();
        assert_eq!(setup.loop_rate_hz, 1000);
        assert_eq!(setup.loop_config.ts_s, 0.001);
        assert_eq!(setup.loop_config.shaping.max_rate_dps, 720.0);
        assert_eq!(setup.loop_config.shaping.max_angle_deg, 45.0);
        assert_eq!(setup.loop_config.idle, 0.05);
        assert_eq!(
            setup.loop_config.modes,
            [
                FlightMode::Attitude,
                FlightMode::RatePid,
                FlightMode::RateLqg
            ]
        );
        assert!(!setup.loop_config.supervisor.arm_on_critical_battery);
        assert_eq!(setup.loop_config.supervisor.failsafe_descent_mps, 0.7);
        assert_eq!(setup.loop_config.supervisor.idle_disarm_ms, 10_000);
        assert_eq!(
            setup.protocol,
            Protocol::Brushed {
                frequency_hz: 32_000
            }
        );
        assert_eq!(setup.control.models[0].ln_beta1, 10.0);
        assert_eq!(setup.control.models[2].ln_beta1, 7.0);
        assert_eq!(setup.control.models[1].tau_s, 0.03);
        assert_eq!(setup.control.pid_rate[2].kp, 0.006);
        assert_eq!(setup.control.pid_rate[0].ki, 0.005);
        // Frame-invariant costs scaled by β1 = e^10 = 22026.5 (roll) and e^7 = 1096.6 (yaw).
        let roll = setup.control.rate_costs[0];
        assert!((roll.q_rate - 1_000.0 / 22_026.47).abs() < 1e-6, "{roll:?}");
        assert!(
            (roll.q_angle - 480_000.0 / 22_026.47).abs() < 1e-3,
            "{roll:?}"
        );
        assert!((roll.q_torque.q3(22_026.47) - 0.1 * 22_026.47).abs() < 1e-2);
        let yaw = setup.control.attitude_costs[2];
        assert!((yaw.q_rate - 1_000.0 / 1_096.63).abs() < 1e-4, "{yaw:?}");
        assert_eq!(setup.battery.cells, None);
        assert_eq!(setup.battery.current_mv_per_amp, Some(50.0));
        assert_eq!(setup.battery.cell_warning_mv, 3_500);
        // And the gains solve from the defaults.
        assert!(Controllers::design(&setup.control).is_ok());
    }

    #[test]
    fn changed_settings_reach_every_consumer() {
        let mut s = Settings::default();
        s.set_text("loop.rate_hz", "500").unwrap();
        s.set_many(&[
            ("output.protocol", Value::U32(1)),
            ("output.rate_hz", Value::U32(400)),
        ])
        .unwrap();
        s.set("output.min_us", Value::U32(1_050)).unwrap();
        s.set("mixer.thrust_expo", Value::F32(0.7)).unwrap();
        s.set("battery.cells", Value::U32(3)).unwrap();
        s.set("battery.current_mv_per_a", Value::F32(0.0)).unwrap();
        s.set_text("mode.switch_high", "sysid").unwrap();
        s.set("failsafe.descent_mps", Value::F32(1.5)).unwrap();
        let setup = from_settings(&s).unwrap();
        assert_eq!(setup.loop_config.ts_s, 0.002);
        assert_eq!(setup.control.ts_s, 0.002);
        assert_eq!(
            setup.protocol,
            Protocol::Pwm {
                rate_hz: 400,
                min_us: 1_050,
                max_us: 2_000
            }
        );
        assert_eq!(
            setup.mixer,
            Mixer::new(QUAD_X, ThrustCurve::Quadratic { k: 0.7 })
        );
        assert_eq!(setup.battery.cells, Some(3));
        assert_eq!(setup.battery.current_mv_per_amp, None);
        assert_eq!(setup.loop_config.modes[2], FlightMode::SystemId);
        assert_eq!(setup.loop_config.supervisor.failsafe_descent_mps, 1.5);
    }

    #[test]
    fn unflyable_settings_are_refused() {
        // `Settings::set` refuses these now; a stored set can still hold them.
        let mut s = Settings::default();
        s.set_by_key(105, 2).unwrap(); // mixer.frame hex-x
        assert_eq!(from_settings(&s), Err(SetupError::FrameNotSupported));
        let mut s = Settings::default();
        s.set_by_key(501, 3_200).unwrap(); // battery.cell_warning_mv
        assert_eq!(from_settings(&s), Err(SetupError::BatteryThresholds));
        assert!(s.set("battery.cell_warning_mv", Value::U32(3_200)).is_err());
    }
}
