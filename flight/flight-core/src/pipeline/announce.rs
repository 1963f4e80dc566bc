//! What the loop and the battery monitor have to say out loud: supervisor decisions and mode
//! changes become one-shot alerts, the battery level a repeating one. The firmware pushes
//! these to its alert task (DAC + buzzer); the SITL feeds them to a `TonePlayer` directly.

use super::flight_loop::LoopOutput;
use crate::alerts::{Alert, TonePlayer};
use crate::battery::BatteryLevel;
use crate::supervisor::Decision;

/// How often a battery alarm repeats while the level lasts, ms.
pub const BATTERY_REPEAT_MS: u32 = 4_000;

/// The alerts one loop output announces: the supervisor's decision, then a mode change.
pub fn loop_alerts(out: &LoopOutput) -> [Option<Alert>; 2] {
    let decision = match out.decision {
        Decision::Steady => None,
        Decision::Armed | Decision::Resumed => Some(Alert::Armed),
        Decision::ArmRefused(_) => Some(Alert::ArmRefused),
        Decision::DisarmedByPilot
        | Decision::DisarmedIdle
        | Decision::DisarmedFailsafe
        | Decision::DisarmedLastResort => Some(Alert::Disarmed),
        Decision::FailsafeEntered => Some(Alert::Failsafe),
        Decision::ControlRecovered => Some(Alert::ControlRecovered),
        Decision::DisarmedSensorFault => Some(Alert::SensorFault),
    };
    [decision, out.mode_changed.then_some(Alert::Mode(out.mode))]
}

/// The repeating alarm for a battery level (`None` when fine).
pub fn battery_alert(level: BatteryLevel) -> Option<Alert> {
    match level {
        BatteryLevel::Ok => None,
        BatteryLevel::Warning => Some(Alert::BatteryWarning),
        BatteryLevel::Critical => Some(Alert::BatteryCritical),
    }
}

/// Feeds a loop output's alerts to `player`.
pub fn announce(player: &mut TonePlayer, out: &LoopOutput) {
    for alert in loop_alerts(out).into_iter().flatten() {
        player.push(alert);
    }
}

/// Sets `player`'s battery alarm for `level`.
pub fn announce_battery(player: &mut TonePlayer, level: BatteryLevel) {
    player.set_repeating(battery_alert(level), BATTERY_REPEAT_MS);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::outputs::Command;
    use crate::supervisor::{ArmBlocker, FlightMode};

    fn output(decision: Decision, mode_changed: bool) -> LoopOutput {
        LoopOutput {
            motors: [Command::Stopped; 4],
            decision,
            mode: FlightMode::Horizon,
            mode_changed,
            armed: false,
            failsafe: false,
            attitude: crate::pipeline::Attitude::LEVEL,
            estimator: crate::pipeline::Source::Complementary,
        }
    }

    #[test]
    fn decisions_and_modes_map_to_distinct_alerts() {
        assert_eq!(loop_alerts(&output(Decision::Steady, false)), [None, None]);
        assert_eq!(
            loop_alerts(&output(Decision::Armed, true)),
            [Some(Alert::Armed), Some(Alert::Mode(FlightMode::Horizon))]
        );
        assert_eq!(
            loop_alerts(&output(
                Decision::ArmRefused(ArmBlocker::GainsNotReady),
                false
            )),
            [Some(Alert::ArmRefused), None]
        );
        assert_eq!(
            loop_alerts(&output(Decision::FailsafeEntered, false))[0],
            Some(Alert::Failsafe)
        );
        // The armed tune starts at 1 kHz, the failsafe one at 600 Hz.
        let mut p = TonePlayer::new();
        announce(&mut p, &output(Decision::Armed, false));
        assert_eq!(p.tick(0), 1000);
        let mut p = TonePlayer::new();
        announce_battery(&mut p, BatteryLevel::Critical);
        assert_eq!(p.tick(0), 4000);
        announce_battery(&mut p, BatteryLevel::Ok);
        assert_eq!(
            battery_alert(BatteryLevel::Warning),
            Some(Alert::BatteryWarning)
        );
    }
}
