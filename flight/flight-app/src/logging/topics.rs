//! The flight log's topics: one fixed-size ULog record each (`taulink_ulog::record!`: the
//! struct, its format string and its encoding from one field list), and [`Entry`], what
//! the ring holds. Sensor topics carry exactly what the estimator was fed, so a replay of
//! them through [`crate::pipeline::Estimator`] recomputes the flown estimate.

use taulink_ulog::record;

record! {
    /// One IMU sample as the flight loop took it (the magnetometer calibrated), with the
    /// loop's two estimator inputs that are not sensor data.
    pub struct SensorImu = "sensor_imu" {
        /// Angular rate, rad/s, body FRD.
        pub gyro_radps: [f32; 3],
        /// Specific force, m/s², body FRD.
        pub accel_mps2: [f32; 3],
        /// Calibrated magnetometer (sensor units) when [`imu_flags::MAG`] is set, else 0.
        pub mag: [f32; 3],
        /// [`imu_flags`].
        pub flags: u8,
    }
}

/// Bits of [`SensorImu::flags`].
pub mod imu_flags {
    /// A fresh magnetometer reading came with this sample.
    pub const MAG: u8 = 1;
    /// The accelerometer corrected the complementary filter on this sample.
    pub const ACCEL_CORRECTS: u8 = 2;
    /// The motors were enabled when the sample was estimated.
    pub const ARMED: u8 = 4;
}

record! {
    /// A barometric altitude handed to the estimator (m, up, standard atmosphere).
    pub struct SensorBaro = "sensor_baro" {
        /// Altitude, m.
        pub altitude_m: f32,
    }
}

record! {
    /// A u-blox NAV-PVT as it arrived (every field the estimator may use).
    pub struct SensorGps = "sensor_gps" {
        /// GPS time of week, ms.
        pub itow_ms: u32,
        /// Fix type (`ubx::FixType` code).
        pub fix_type: u8,
        /// NAV-PVT flags.
        pub flags: u8,
        /// Satellites used.
        pub num_sv: u8,
        /// Longitude, deg·1e-7.
        pub lon_e7: i32,
        /// Latitude, deg·1e-7.
        pub lat_e7: i32,
        /// Height above the ellipsoid, mm.
        pub height_mm: i32,
        /// Height above mean sea level, mm.
        pub h_msl_mm: i32,
        /// Horizontal accuracy, mm.
        pub h_acc_mm: u32,
        /// Vertical accuracy, mm.
        pub v_acc_mm: u32,
        /// Velocity north, east, down, mm/s.
        pub vel_ned_mmps: [i32; 3],
        /// Ground speed, mm/s.
        pub g_speed_mmps: i32,
        /// Heading of motion, deg·1e-5.
        pub head_mot_e5: i32,
        /// Speed accuracy, mm/s.
        pub s_acc_mmps: u32,
        /// Position DOP ·0.01.
        pub p_dop_e2: u16,
    }
}

record! {
    /// The estimate the loop flew on (NaN where the flying estimator has no value).
    pub struct Estimate = "estimate" {
        /// Attitude body FRD → NED, w x y z.
        pub q: [f32; 4],
        /// Roll, pitch, yaw, deg.
        pub euler_deg: [f32; 3],
        /// INS velocity NED, m/s.
        pub velocity_ned_mps: [f32; 3],
        /// INS position NED, m (north and east from home, down from the baro origin).
        pub position_ned_m: [f32; 3],
        /// INS gyro bias, rad/s.
        pub gyro_bias_radps: [f32; 3],
        /// INS z accelerometer bias, m/s².
        pub accel_bias_z_mps2: f32,
        /// Altitude above the power-up point, m (INS, or the tracked baro).
        pub altitude_m: f32,
        /// Climb rate, m/s up (the loop's blend).
        pub climb_mps: f32,
        /// The estimator flying: 0 complementary, 1 INS.
        pub source: u8,
    }
}

record! {
    /// What the pilot asks through the link.
    pub struct Setpoint = "setpoint" {
        /// Roll, pitch, yaw (−1…1) and throttle (0…1) sticks.
        pub sticks: [f32; 4],
        /// The mode switch channel, −1…1.
        pub mode_channel: f32,
        /// Arm switch: 0 off, 1 on, 2 none configured.
        pub arm_switch: u8,
        /// Fresh channels (not in failsafe).
        pub link_up: bool,
    }
}

record! {
    /// The motor commands (0…1; −1 for a stopped motor).
    pub struct Motors = "motors" {
        /// Motors 1–4.
        pub command: [f32; 4],
    }
}

record! {
    /// The supervisor and health state.
    pub struct Status = "status" {
        /// Motors may turn.
        pub armed: bool,
        /// Flight mode (`FlightMode::id`).
        pub mode: u8,
        /// Link failsafe active.
        pub failsafe: bool,
        /// The estimator flying: 0 complementary, 1 INS.
        pub estimator: u8,
        /// Arming blockers (telemetry's bit set).
        pub arming_blockers: u16,
        /// Standing IMU fault: 0 none, 1 stalled, 2 read error, 3 frozen, 4 implausible.
        pub imu_fault: u8,
    }
}

record! {
    /// A battery reading.
    pub struct Battery = "battery_status" {
        /// Filtered pack voltage, V.
        pub voltage_v: f32,
        /// Current, A.
        pub current_a: f32,
        /// Charge used, mAh.
        pub consumed_mah: u32,
        /// Cells in series (0 unknown).
        pub cells: u8,
        /// Level: 0 ok, 1 warning, 2 critical.
        pub level: u8,
    }
}

record! {
    /// The radio link as the flight side sees it.
    pub struct LinkStats = "link_stats" {
        /// Uplink RSSI, dBm.
        pub rssi_dbm: i8,
        /// Uplink link quality, %.
        pub lq_percent: u8,
        /// The module's downlink RSSI, dBm (0: no report).
        pub down_rssi_dbm: i8,
        /// The module's downlink LQ, % (0: no report).
        pub down_lq_percent: u8,
        /// Rate mode wire code.
        pub rate_mode: u8,
        /// Valid uplink packets.
        pub received: u32,
        /// Missed uplink packets.
        pub missed: u32,
        /// Failsafe events since boot.
        pub failsafes: u16,
    }
}

record! {
    /// The system identification (in progress while the mode flies, then the result).
    pub struct Identification = "identification" {
        /// ln β per axis (roll, pitch, yaw).
        pub ln_beta: [f32; 3],
        /// Motor time constant τ, s.
        pub tau_s: f32,
        /// Input bias per axis.
        pub bias: [f32; 3],
        /// 1σ of each ln β.
        pub sigma_ln_beta: [f32; 3],
        /// 1σ of ln τ.
        pub sigma_ln_tau: f32,
        /// RMS gyro innovation per axis, deg/s.
        pub gyro_noise_dps: [f32; 3],
        /// Samples processed.
        pub samples: u32,
        /// The identification has finished (the mode was left).
        pub finished: bool,
    }
}

/// Events logged as ULog strings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// The supervisor's decision (only non-steady ones are logged).
    Decision(crate::supervisor::Decision),
    /// The flight mode changed to this one.
    Mode(crate::supervisor::FlightMode),
    /// The INS fell back to the complementary filter.
    EstimatorFallback,
    /// A new setup was installed (the loop and its estimator started afresh: a replay
    /// restarts its estimator here).
    LoopRestarted,
    /// The IMU delivered nothing usable (the ride-through began).
    ImuFault,
}

/// One entry of the log's ring: a topic sample, an event, or a mark of lost entries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Entry {
    /// IMU.
    Imu(SensorImu),
    /// Baro.
    Baro(SensorBaro),
    /// GPS.
    Gps(SensorGps),
    /// Estimate.
    Estimate(Estimate),
    /// Pilot setpoint.
    Setpoint(Setpoint),
    /// Motor commands.
    Motors(Motors),
    /// Supervisor state.
    Status(Status),
    /// Battery.
    Battery(Battery),
    /// Link statistics.
    Link(LinkStats),
    /// Identification.
    Identification(Identification),
    /// An event at a time, µs.
    Event(u64, Event),
    /// Entries of this long were lost (the ring was full), ms.
    Dropout(u64, u16),
}
