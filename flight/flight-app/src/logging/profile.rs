//! Log profiles: which topics are logged how often. The pilot chooses one with the setting
//! `log.profile`; the bytes per second each profile costs are measured into the flight
//! README (`cargo run --release -p flight-sitl -- log-figures --write`).

/// A log profile (the `log.profile` choice, in [`telemetry::settings::LOG_PROFILES`]
/// order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Profile {
    /// Nothing is logged.
    Off,
    /// What the telemetry channel's leftover goodput carries (under 1 kB/s, below M100's
    /// downlink): the estimate and motors at 5 Hz, the rest slower; no raw IMU.
    Link,
    /// For the Sparky2's flash (≈ 3.4 kB/s: five minutes in its 1 MiB log area): raw IMU at
    /// 20 Hz, the estimate, sticks and motors at 10 Hz, every fifth baro, every GPS fix.
    Flight,
    /// Everything at its own rate (IMU, estimate, sticks and motors every loop): what a
    /// replay through the estimator needs to reproduce the flight bit for bit.
    Full,
}

impl Profile {
    /// Every profile, in setting order.
    pub const ALL: [Profile; 4] = [Profile::Off, Profile::Link, Profile::Flight, Profile::Full];

    /// The profile of the setting's choice index (`Off` for an unknown one).
    pub fn from_index(index: u32) -> Self {
        Self::ALL
            .get(index as usize)
            .copied()
            .unwrap_or(Profile::Off)
    }

    /// Its index among the setting's choices.
    pub fn index(self) -> u32 {
        Self::ALL.iter().position(|p| *p == self).unwrap_or(0) as u32
    }

    /// The setting's name for it.
    pub fn name(self) -> &'static str {
        match self {
            Profile::Off => "off",
            Profile::Link => "link",
            Profile::Flight => "flight",
            Profile::Full => "full",
        }
    }

    /// The rates of its topics.
    pub const fn rates(self) -> Rates {
        match self {
            Profile::Off => Rates {
                imu_hz: 0,
                estimate_hz: 0,
                setpoint_hz: 0,
                motors_hz: 0,
                status_hz: 0,
                identification_hz: 0,
                baro_every: 0,
                gps_every: 0,
                battery_every: 0,
                link_every: 0,
            },
            Profile::Link => Rates {
                imu_hz: 0,
                estimate_hz: 5,
                setpoint_hz: 2,
                motors_hz: 5,
                status_hz: 2,
                identification_hz: 2,
                baro_every: 25,
                gps_every: 5,
                battery_every: 50,
                link_every: 40,
            },
            Profile::Flight => Rates {
                imu_hz: 20,
                estimate_hz: 10,
                setpoint_hz: 10,
                motors_hz: 10,
                status_hz: 5,
                identification_hz: 5,
                baro_every: 5,
                gps_every: 1,
                battery_every: 10,
                link_every: 20,
            },
            Profile::Full => Rates {
                imu_hz: u16::MAX,
                estimate_hz: u16::MAX,
                setpoint_hz: u16::MAX,
                motors_hz: u16::MAX,
                status_hz: 50,
                identification_hz: 50,
                baro_every: 1,
                gps_every: 1,
                battery_every: 1,
                link_every: 1,
            },
        }
    }
}

/// How often each topic is logged: loop topics in Hz (0 off; at or above the loop rate:
/// every loop), event topics as every n-th event (0 off).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rates {
    /// Raw IMU samples.
    pub imu_hz: u16,
    /// The estimate.
    pub estimate_hz: u16,
    /// The pilot's sticks.
    pub setpoint_hz: u16,
    /// Motor commands.
    pub motors_hz: u16,
    /// Supervisor state.
    pub status_hz: u16,
    /// Identification in progress.
    pub identification_hz: u16,
    /// Baro readings.
    pub baro_every: u16,
    /// GPS fixes.
    pub gps_every: u16,
    /// Battery readings.
    pub battery_every: u16,
    /// Link reports.
    pub link_every: u16,
}

/// Loops between two samples of a loop topic at `hz` with the loop at `loop_hz` (0: off).
pub(super) fn divider(hz: u16, loop_hz: u32) -> u32 {
    if hz == 0 {
        0
    } else {
        (loop_hz / u32::from(hz)).max(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dividers_follow_the_loop_rate() {
        assert_eq!(divider(100, 1000), 10);
        assert_eq!(divider(100, 500), 5);
        assert_eq!(divider(u16::MAX, 1000), 1);
        assert_eq!(divider(0, 1000), 0);
        assert_eq!(Profile::from_index(3), Profile::Full);
        assert_eq!(Profile::from_index(9), Profile::Off);
        assert_eq!(
            Profile::from_index(Profile::Flight.index()),
            Profile::Flight
        );
        for (i, p) in Profile::ALL.iter().enumerate() {
            assert_eq!(
                telemetry::settings::LOG_PROFILES[i],
                p.name(),
                "setting order"
            );
        }
    }
}
