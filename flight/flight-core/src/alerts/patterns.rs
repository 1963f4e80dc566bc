//! The tone patterns. Each alert has its own rhythm and pitch so a pilot can tell them apart
//! through the video receiver's audio without looking.

use crate::supervisor::FlightMode;

/// One tone (or a pause, at 0 Hz).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tone {
    /// Pitch, Hz; 0 is silence.
    pub frequency_hz: u16,
    /// Length, ms.
    pub duration_ms: u16,
}

const fn t(frequency_hz: u16, duration_ms: u16) -> Tone {
    Tone {
        frequency_hz,
        duration_ms,
    }
}

// Fast high triplets: unmistakable.
const BATTERY_CRITICAL: &[Tone] = &[
    t(4000, 80),
    t(0, 40),
    t(4000, 80),
    t(0, 40),
    t(4000, 80),
    t(0, 300),
];
// Three long low tones.
const FAILSAFE: &[Tone] = &[
    t(600, 400),
    t(0, 150),
    t(600, 400),
    t(0, 150),
    t(600, 400),
    t(0, 300),
];
// Tau Labs' alarm rhythm: pause, three short, one long.
const BATTERY_WARNING: &[Tone] = &[
    t(0, 240),
    t(2500, 80),
    t(0, 80),
    t(2500, 80),
    t(0, 80),
    t(2500, 80),
    t(0, 80),
    t(2500, 400),
];
// Alternating high-low siren, fast: the IMU failed and the motors were stopped.
const SENSOR_FAULT: &[Tone] = &[
    t(3500, 100),
    t(800, 100),
    t(3500, 100),
    t(800, 100),
    t(3500, 100),
    t(800, 100),
    t(0, 300),
];
// Rising pair.
const ARMED: &[Tone] = &[t(1000, 150), t(2000, 300)];
// Falling pair.
const DISARMED: &[Tone] = &[t(2000, 150), t(1000, 300)];
// A low buzz.
const ARM_REFUSED: &[Tone] = &[t(300, 600)];
// The magnetometer calibration: a slow rising triple when collecting starts, a rising
// run ending high when it is stored, a falling low pair when the readings were refused.
const MAGCAL_STARTED: &[Tone] = &[t(800, 200), t(0, 80), t(1200, 200), t(0, 80), t(1600, 200)];
const MAGCAL_STORED: &[Tone] = &[t(1200, 100), t(1600, 100), t(2000, 100), t(2400, 400)];
const MAGCAL_REFUSED: &[Tone] = &[t(700, 300), t(0, 80), t(400, 600)];
// Two rising chirps.
const CONTROL_RECOVERED: &[Tone] = &[t(1500, 100), t(0, 60), t(2500, 200)];
// Mode beeps: n short beeps at a mid pitch for the n-th mode.
const MODE_1: &[Tone] = &[t(3000, 60)];
const MODE_2: &[Tone] = &[t(3000, 60), t(0, 100), t(3000, 60)];
const MODE_3: &[Tone] = &[t(3000, 60), t(0, 100), t(3000, 60), t(0, 100), t(3000, 60)];
const MODE_4: &[Tone] = &[
    t(3000, 60),
    t(0, 100),
    t(3000, 60),
    t(0, 100),
    t(3000, 60),
    t(0, 100),
    t(3000, 60),
];
// System identification: a long high-low pair.
const MODE_SYSID: &[Tone] = &[t(3000, 300), t(0, 100), t(1500, 300)];

/// Something worth a sound.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Alert {
    /// The IMU failed; the motors were stopped (disarmed, re-arm needed).
    SensorFault,
    /// Battery critical: land now (repeats while critical).
    BatteryCritical,
    /// Link lost while armed.
    Failsafe,
    /// Battery warning (repeats while low).
    BatteryWarning,
    /// Armed.
    Armed,
    /// Disarmed.
    Disarmed,
    /// An arm attempt was refused.
    ArmRefused,
    /// The pilot has control again after a failsafe.
    ControlRecovered,
    /// Flight mode changed.
    Mode(FlightMode),
    /// The magnetometer calibration started collecting (stick gesture, disarmed).
    MagcalStarted,
    /// The magnetometer calibration was stored (and is being saved).
    MagcalStored,
    /// The magnetometer calibration's readings failed its checks; nothing was stored.
    MagcalRefused,
}

impl Alert {
    /// Higher plays first and may cut a lower one short.
    pub const fn priority(self) -> u8 {
        match self {
            Alert::SensorFault => 8,
            Alert::BatteryCritical => 7,
            Alert::Failsafe => 6,
            Alert::BatteryWarning => 5,
            Alert::ArmRefused | Alert::MagcalRefused => 4,
            Alert::MagcalStarted | Alert::MagcalStored => 3,
            Alert::Armed | Alert::Disarmed => 3,
            Alert::ControlRecovered => 2,
            Alert::Mode(_) => 1,
        }
    }

    /// The pattern.
    pub const fn tones(self) -> &'static [Tone] {
        match self {
            Alert::SensorFault => SENSOR_FAULT,
            Alert::BatteryCritical => BATTERY_CRITICAL,
            Alert::Failsafe => FAILSAFE,
            Alert::BatteryWarning => BATTERY_WARNING,
            Alert::Armed => ARMED,
            Alert::Disarmed => DISARMED,
            Alert::ArmRefused => ARM_REFUSED,
            Alert::ControlRecovered => CONTROL_RECOVERED,
            Alert::MagcalStarted => MAGCAL_STARTED,
            Alert::MagcalStored => MAGCAL_STORED,
            Alert::MagcalRefused => MAGCAL_REFUSED,
            Alert::Mode(m) => match m {
                FlightMode::RatePid => MODE_1,
                FlightMode::RateLqg => MODE_2,
                // The hold modes fly on the attitude law: its tone.
                FlightMode::Attitude
                | FlightMode::AltitudeHold
                | FlightMode::PositionHold
                | FlightMode::Loiter => MODE_3,
                FlightMode::Horizon => MODE_4,
                FlightMode::SystemId => MODE_SYSID,
            },
        }
    }
}
