//! The stateless halves of the flight loop's controller and mix stages: what the active
//! flight mode's controller asks for (nothing on the ground), the angle setpoint of the
//! failsafe guidance, and the mix into motor commands. `FlightLoop::step` owns the order
//! and the state; these only compute.

use super::controllers::Controllers;
use super::flight_loop::LoopConfig;
use super::identify::{Sysid, sysid_output};
use crate::control::lqr::AxisSetpoint;
use crate::control::mixer::Mixer;
use crate::outputs::Command;
use crate::supervisor::{FlightMode, Sticks};

/// The sticks as the setpoint stage flies them. With stick arming (no arm switch) and the
/// throttle low, the yaw stick is the arm/disarm gesture, not a yaw demand (Betaflight
/// gives stick armers the same yaw deadband): in air mode a full yaw demand spins the
/// motors up to make room for it, and on the ground after a landing that lifted the frame
/// before the disarm gesture's hold completed. Roll and pitch stay flown (air mode).
pub(super) fn flown_sticks(sticks: &Sticks, arm_switch: bool) -> Sticks {
    if !arm_switch && sticks.throttle_low() {
        Sticks {
            yaw: 0.0,
            ..*sticks
        }
    } else {
        *sticks
    }
}

/// Failsafe: roll and pitch held at the target (level without a fix, the position hold's
/// angles with one), no yaw rotation.
pub(super) fn angle_setpoint(
    [roll_sp, pitch_sp]: [f32; 2],
    [roll, pitch]: [f32; 2],
) -> [AxisSetpoint; 3] {
    [
        AxisSetpoint::Attitude {
            angle_error_deg: roll_sp - roll,
        },
        AxisSetpoint::Attitude {
            angle_error_deg: pitch_sp - pitch,
        },
        AxisSetpoint::Rate { rate_dps: 0.0 },
    ]
}

/// Setpoint stage: the sticks through the active mode's controller. Returns the
/// roll/pitch/yaw demand and whether the identification shake is on. `hold_angles_deg`:
/// the hold modes' roll/pitch setpoints when their loops fly the frame (else the sticks').
#[allow(clippy::too_many_arguments)]
pub(super) fn setpoint(
    c: &mut Controllers,
    sysid: &mut Option<Sysid>,
    config: &LoopConfig,
    mode: FlightMode,
    sticks: &Sticks,
    gyro_dps: [f32; 3],
    [roll, pitch]: [f32; 2],
    hold_angles_deg: Option<[f32; 2]>,
) -> ([f32; 3], bool) {
    // Roll and pitch rates only in the modes that fly them (attitude mode does not).
    let rates = || config.shaping.rates_dps(sticks);
    let yaw_rate = config.shaping.yaw_rate_dps(sticks);
    let [roll_sp, pitch_sp] = hold_angles_deg.unwrap_or_else(|| config.shaping.angles_deg(sticks));
    let errors = [roll_sp - roll, pitch_sp - pitch];
    let out = match mode {
        FlightMode::RatePid => c.pid_rate(gyro_dps, rates()),
        // On the ground (throttle low) nothing shakes: the output is zeroed by the loop,
        // and the EKF only learns in the air.
        FlightMode::SystemId if sticks.throttle_low() => [0.0; 3],
        FlightMode::SystemId => {
            let out = sysid_output(sysid, config.ts_s, gyro_dps, errors, yaw_rate, c);
            return (out, true);
        }
        FlightMode::RateLqg => c.lqg(
            gyro_dps,
            rates().map(|rate_dps| AxisSetpoint::Rate { rate_dps }),
        ),
        FlightMode::Attitude
        | FlightMode::AltitudeHold
        | FlightMode::PositionHold
        | FlightMode::Loiter
            if !config.attitude_uses_lqg =>
        {
            c.pid_attitude(gyro_dps, errors, yaw_rate)
        }
        FlightMode::Attitude
        | FlightMode::AltitudeHold
        | FlightMode::PositionHold
        | FlightMode::Loiter => c.lqg(
            gyro_dps,
            [
                AxisSetpoint::Attitude {
                    angle_error_deg: errors[0],
                },
                AxisSetpoint::Attitude {
                    angle_error_deg: errors[1],
                },
                AxisSetpoint::Rate { rate_dps: yaw_rate },
            ],
        ),
        FlightMode::Horizon => {
            let w = config.shaping.horizon_weight(sticks);
            let rates = rates();
            let blend = |i: usize| AxisSetpoint::Blend {
                rate_dps: rates.get(i).copied().unwrap_or(0.0),
                angle_error_deg: errors.get(i).copied().unwrap_or(0.0),
                attitude_weight: w,
            };
            c.lqg(
                gyro_dps,
                [
                    blend(0),
                    blend(1),
                    AxisSetpoint::Rate { rate_dps: yaw_rate },
                ],
            )
        }
    };
    (out, false)
}

/// The pilot's controller output, or nothing on the ground. Throttle at the bottom before
/// the first take-off, or after the touchdown detector saw the frame land, means sitting on
/// the ground: the controllers neither act nor wind up (motors at idle), or a held arm or
/// disarm gesture would spin the frame up and lift it. In the air a closed throttle keeps
/// full stabilisation (air mode) until that touchdown.
pub(super) fn ground_idle(
    c: &mut Controllers,
    out: [f32; 3],
    sticks: &Sticks,
    on_ground: bool,
    gyro_dps: [f32; 3],
) -> [f32; 3] {
    if sticks.throttle_low() && on_ground {
        c.reset(gyro_dps);
        [0.0; 3]
    } else {
        out
    }
}

/// Whether `mode`'s controller is the LQG, which predicts with its own output (the mix
/// tells it what the motors realise).
pub(super) fn uses_lqg(mode: FlightMode, config: &LoopConfig) -> bool {
    match mode {
        FlightMode::RateLqg | FlightMode::Horizon => true,
        FlightMode::Attitude
        | FlightMode::AltitudeHold
        | FlightMode::PositionHold
        | FlightMode::Loiter => config.attitude_uses_lqg,
        FlightMode::RatePid | FlightMode::SystemId => false,
    }
}

/// The configured idle command limited to 0…0.3 (worked out once, not per loop).
pub(super) fn idle(configured: f32) -> f32 {
    configured.clamp(0.0, 0.3)
}

/// What the flying stages hand to the mix.
pub(super) struct Demand {
    /// Collective throttle, 0…1.
    pub throttle: f32,
    /// Roll, pitch, yaw demand, −1…1.
    pub attitude: [f32; 3],
    /// Motor command at zero throttle, already limited to 0…0.3 ([`idle`]).
    pub idle: f32,
    /// The active controller predicts with its own output (told what was realised).
    pub uses_lqg: bool,
}

/// Mix stage: throttle and attitude demand into motor commands above idle. Controllers
/// that predict with their own output, and a running identification, are told what the
/// motors realise (desaturation scales the demand down whenever it does not fit).
pub(super) fn mix(
    c: &mut Controllers,
    mixer: &Mixer<4>,
    sysid: Option<&mut Sysid>,
    demand: Demand,
) -> [Command; 4] {
    let idle = demand.idle;
    let (mixed, applied) = mixer.mix_with_applied(demand.throttle, demand.attitude);
    // Undesaturated (the usual case) the LQG's own outputs were realised: nothing to tell.
    if demand.uses_lqg && applied != demand.attitude {
        c.lqg_realised(applied);
    }
    if let Some(s) = sysid {
        s.ekf.record_output(applied);
    }
    let mut motors = [Command::Stopped; 4];
    for (m, x) in motors.iter_mut().zip(mixed) {
        *m = Command::Throttle(idle + (1.0 - idle) * x);
    }
    motors
}
