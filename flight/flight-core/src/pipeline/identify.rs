//! The system-identification flight mode: the shake (`control/LQG.md` §5) on top of self-levelling
//! attitude control, and the 13-state EKF that identifies β and τ from the gyro and the
//! output actually sent. The loop starts it on entering the mode in the air and keeps the
//! result when the mode is left (`FlightLoop::take_identification`).

use super::controllers::Controllers;
use crate::sysid::ekf::{SysidConfig, SystemIdentifier};
use crate::sysid::shake::Shake;

/// Length of one shake phase (Tau Labs: 75 ms).
const SHAKE_PHASE_S: f32 = 0.075;

/// A running identification: the excitation and the EKF watching its effect.
#[derive(Debug, Clone)]
pub(super) struct Sysid {
    shake: Shake,
    /// The identification EKF.
    pub(super) ekf: SystemIdentifier,
}

/// System identification: the attitude PID holds the frame level (hands-off safe) and
/// the shake adds its square offsets; the EKF sees the gyro here and, from the loop, the
/// output the motors actually realised.
pub(super) fn sysid_output(
    sysid: &mut Option<Sysid>,
    ts_s: f32,
    gyro_dps: [f32; 3],
    errors: [f32; 2],
    yaw_rate_dps: f32,
    c: &mut Controllers,
) -> [f32; 3] {
    let s = sysid.get_or_insert_with(|| {
        let mut cfg = SysidConfig::new(ts_s);
        // Synchronous outputs act one loop after they are computed.
        cfg.output_delay_samples = 1;
        Sysid {
            shake: Shake::new(ts_s, SHAKE_PHASE_S),
            ekf: SystemIdentifier::new(cfg),
        }
    });
    s.ekf.update(gyro_dps);
    let offsets = s.shake.next(s.ekf.ln_beta());
    let stabilise = c.pid_attitude(gyro_dps, errors, yaw_rate_dps);
    let mut u = [0.0f32; 3];
    for ((o, a), b) in u.iter_mut().zip(stabilise).zip(offsets) {
        *o = (a + b).clamp(-1.0, 1.0);
    }
    // The loop tells the EKF what the mixer realised of `u` (`record_output`), not `u`.
    u
}
