//! What flies the frame this loop, before the controllers: the link failsafe's guidance
//! ([`super::failsafe`]), else a hold mode's loops, else the pilot's sticks — as the
//! collective throttle and the roll/pitch angle setpoints the controllers are given.

use super::hold::{Hold, Horizontal, Nav};
use crate::supervisor::{FlightMode, ModePolicy, Sticks};

/// This loop's guidance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Guidance {
    /// The link failsafe: its throttle, and roll/pitch held at these angles (deg; level
    /// without a fix) by the LQG.
    Failsafe {
        /// Collective throttle, 0…1.
        throttle: f32,
        /// Roll and pitch setpoints, deg.
        angles_deg: [f32; 2],
    },
    /// A hold mode's loops: their throttle, and their roll/pitch angles when the
    /// horizontal loop flies the frame (`None`: the sticks fly attitude mode).
    Hold {
        /// Collective throttle, 0…1.
        throttle: f32,
        /// Roll and pitch setpoints, deg.
        angles_deg: Option<[f32; 2]>,
    },
    /// The pilot's sticks through the mode's controller.
    Sticks,
}

impl Guidance {
    /// The collective throttle, the stick's (limited to 0…1) where nothing else sets it.
    #[inline(always)]
    pub fn throttle(&self, sticks: &Sticks) -> f32 {
        match *self {
            Self::Failsafe { throttle, .. } | Self::Hold { throttle, .. } => throttle,
            Self::Sticks => sticks.throttle.clamp(0.0, 1.0),
        }
    }

    /// The link failsafe flies (the LQG holds its angles).
    #[inline(always)]
    pub fn is_failsafe(&self) -> bool {
        matches!(self, Self::Failsafe { .. })
    }

    /// The hold loops' roll/pitch angles when they fly the frame.
    #[inline(always)]
    pub fn hold_angles(&self) -> Option<[f32; 2]> {
        match *self {
            Self::Hold { angles_deg, .. } => angles_deg,
            Self::Failsafe { .. } | Self::Sticks => None,
        }
    }
}

/// The pilot's guidance outside a failsafe: a hold mode's loops when `mode` holds and the
/// navigation estimate is there, else the sticks.
#[inline(always)]
pub(super) fn pilot(
    mode: FlightMode,
    hold: &mut Hold,
    nav: Option<Nav>,
    sticks: &Sticks,
    hover_throttle: f32,
    ts_s: f32,
) -> Guidance {
    let (true, Some(nav)) = (mode.holds(), nav) else {
        return Guidance::Sticks;
    };
    let throttle = hold.throttle(sticks.throttle, &nav, hover_throttle, ts_s);
    let horizontal = match mode {
        FlightMode::PositionHold => Some(Horizontal::PositionHold),
        FlightMode::Loiter => Some(Horizontal::Loiter),
        _ => None,
    };
    let angles_deg =
        horizontal.and_then(|h| hold.angles(h, [sticks.roll, sticks.pitch], &nav, ts_s));
    Guidance::Hold {
        throttle,
        angles_deg,
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    const TS: f32 = 0.002;
    const HOVER: f32 = 0.4;

    /// At 10 m, level, facing north; `fix`: a good fix 2 m north of the origin (the
    /// failsafe guidance's tests fly from it too).
    pub(in crate::pipeline) fn nav(fix: bool) -> Nav {
        Nav {
            vertical: Some((10.0, 0.0)),
            climb_mps: Some(0.0),
            horizontal: fix.then_some(([2.0, 0.0], [0.0, 0.0])),
            yaw_cos_sin: [1.0, 0.0],
        }
    }

    fn sticks(throttle: f32, roll: f32, pitch: f32) -> Sticks {
        Sticks {
            throttle,
            roll,
            pitch,
            yaw: 0.0,
        }
    }

    #[test]
    fn modes_that_do_not_hold_fly_the_sticks() {
        let mut hold = Hold::default();
        let n = nav(true);
        for mode in [
            FlightMode::Attitude,
            FlightMode::RatePid,
            FlightMode::RateLqg,
            FlightMode::Horizon,
            FlightMode::SystemId,
        ] {
            let s = sticks(0.7, 0.2, 0.0);
            let g = pilot(mode, &mut hold, Some(n), &s, HOVER, TS);
            assert_eq!(g, Guidance::Sticks, "{mode:?}");
            assert_eq!(g.throttle(&s), 0.7);
            assert_eq!(g.hold_angles(), None);
        }
        assert_eq!(hold, Hold::default(), "the hold loops untouched");
        // The stick's throttle is limited to 0…1.
        assert_eq!(Guidance::Sticks.throttle(&sticks(1.3, 0.0, 0.0)), 1.0);
    }

    #[test]
    fn a_hold_mode_without_the_navigation_estimate_flies_the_sticks() {
        let mut hold = Hold::default();
        let s = sticks(0.5, 0.0, 0.0);
        let g = pilot(FlightMode::AltitudeHold, &mut hold, None, &s, HOVER, TS);
        assert_eq!(g, Guidance::Sticks);
    }

    #[test]
    fn altitude_hold_holds_the_altitude_and_leaves_the_angles_to_the_sticks() {
        let mut hold = Hold::default();
        let n = nav(true);
        let s = sticks(0.5, 0.3, 0.0);
        let g = pilot(FlightMode::AltitudeHold, &mut hold, Some(n), &s, HOVER, TS);
        assert_eq!(
            g,
            Guidance::Hold {
                throttle: HOVER,
                angles_deg: None
            }
        );
        assert_eq!(hold.altitude_target(), Some(10.0));
        assert_eq!(hold.position_target(), None);
        // Full throttle stick: climbs at 1.5 m/s, 0.15 above the hover throttle.
        let g = pilot(
            FlightMode::AltitudeHold,
            &mut hold,
            Some(n),
            &sticks(1.0, 0.0, 0.0),
            HOVER,
            TS,
        );
        assert!((g.throttle(&s) - (HOVER + 0.15)).abs() < 1e-3, "{g:?}");
    }

    #[test]
    fn position_hold_and_loiter_fly_the_horizontal_loop_with_a_fix() {
        let n = nav(true);
        let centred = sticks(0.5, 0.0, 0.0);
        for mode in [FlightMode::PositionHold, FlightMode::Loiter] {
            let mut hold = Hold::default();
            let g = pilot(mode, &mut hold, Some(n), &centred, HOVER, TS);
            assert_eq!(g.hold_angles(), Some([0.0, 0.0]), "{mode:?}");
            assert_eq!(hold.position_target(), Some([2.0, 0.0]), "{mode:?}");
        }
        // Deflected sticks in position hold: the pilot flies the angles, the altitude held.
        let mut hold = Hold::default();
        let s = sticks(0.5, 0.5, 0.0);
        let g = pilot(FlightMode::PositionHold, &mut hold, Some(n), &s, HOVER, TS);
        assert_eq!(
            g,
            Guidance::Hold {
                throttle: HOVER,
                angles_deg: None
            }
        );
        // Without a fix: the altitude held, the sticks fly the angles.
        let g = pilot(
            FlightMode::Loiter,
            &mut hold,
            Some(nav(false)),
            &centred,
            HOVER,
            TS,
        );
        assert_eq!(g.hold_angles(), None);
        assert!(!g.is_failsafe());
    }
}
