//! The table itself: every flight setting with its key, name, range, factory value and
//! meaning, and the words of each choice. Rows are only ever appended (the index is the
//! `SettingChange` id and the stored order); a retired key is never reused.

use core::marker::PhantomData;

use super::handle::{Row, table};
use super::{Choice, Kind, Param, Value};

const fn f(key: u16, name: &'static str, min: f32, max: f32, default: f32) -> Row<f32> {
    Row {
        param: Param {
            key,
            name,
            kind: Kind::F32 { min, max },
            default: Value::F32(default),
        },
        _type: PhantomData,
    }
}

const fn u(key: u16, name: &'static str, min: u32, max: u32, default: u32) -> Row<u32> {
    Row {
        param: Param {
            key,
            name,
            kind: Kind::U32 { min, max },
            default: Value::U32(default),
        },
        _type: PhantomData,
    }
}

const fn c(key: u16, name: &'static str, choice: Choice, default: u32) -> Row<u32> {
    Row {
        param: Param {
            key,
            name,
            kind: Kind::Choice(choice),
            default: Value::U32(default),
        },
        _type: PhantomData,
    }
}

/// Output protocols, in `flight_core::outputs::Protocol` order.
pub const OUTPUT_PROTOCOLS: Choice = &["brushed", "pwm", "oneshot125"];
/// Mixer frames.
pub const FRAMES: Choice = &["quad-x", "quad-plus", "hex-x"];
/// Flight modes for the three switch positions.
pub const MODES: Choice = &[
    "rate-pid",
    "rate-lqg",
    "attitude",
    "horizon",
    "sysid",
    "altitude-hold",
    "position-hold",
    "loiter",
];
/// Link bands, in [`crate::link::Band`] order (`ism433`: the licence-exempt 433.05–434.79 MHz
/// only).
pub const BANDS: Choice = &["433", "868", "915", "ism433"];
/// Link rate modes, in [`crate::link::RateMode::ALL`] order, as the spec and both ends
/// write them.
pub const RATES: Choice = &["L50", "M100", "F250", "F500", "F700"];
/// Uplink channel formats (`crate::channels::ChannelFormat`).
pub const CHANNEL_FORMATS: Choice = &["16", "8", "16-sticks"];
/// Air protocols (`link.protocol` on the flight side, `protocol` on the module): TauLink,
/// OpenLRSng 3.8, OpenLRSng 3.9. OpenLRSng frames carry no authentication.
pub const PROTOCOLS: Choice = &["taulink", "openlrs38", "openlrs39"];
/// Arming at a critical battery: refused (factory) or allowed.
pub const ARM_ON_CRITICAL: Choice = &["refuse", "allow"];
/// Gyro loop rates.
pub const LOOP_RATES: Choice = &["500", "1000"];
/// Estimators: the complementary filter alone, the INS with GPS, the INS without GPS
/// (horizontal velocity held by a pseudo-measurement).
pub const INS_MODES: Choice = &["complementary", "ins", "ins_indoor"];
/// VTX bands (`flight_core::vtx::Band`): the BrushedSparky's VTX module's band-select pins.
pub const VTX_BANDS: Choice = &["a", "b", "e", "airwave"];
/// Flight-log profiles (`flight_app::logging::Profile`): off, the telemetry channel's, the
/// Sparky2 flash's, every sample (replay-grade).
pub const LOG_PROFILES: Choice = &["off", "link", "flight", "full"];

table! {
    // outputs (1xx)
    /// How the motor outputs are driven: brushed PWM duty, servo PWM or OneShot125.
    OUTPUT_PROTOCOL: u32 = c(100, "output.protocol", OUTPUT_PROTOCOLS, 0),
    /// The motor outputs' update rate (brushed: the PWM frequency).
    OUTPUT_RATE_HZ: u32 = u(101, "output.rate_hz", 50, 64_000, 32_000),
    /// Pulse length of a stopped motor (PWM, OneShot125 scaled by 1/8).
    OUTPUT_MIN_US: u32 = u(102, "output.min_us", 500, 2_500, 1_000),
    /// Pulse length of full throttle (PWM, OneShot125 scaled by 1/8).
    OUTPUT_MAX_US: u32 = u(103, "output.max_us", 500, 2_500, 2_000),
    /// Throttle fraction an armed motor never drops below.
    OUTPUT_IDLE: f32 = f(104, "output.idle", 0.0, 0.3, 0.05),
    /// The frame's motor layout the mixer drives.
    MIXER_FRAME: u32 = c(105, "mixer.frame", FRAMES, 0),
    /// Thrust curve: 0 linear in command, 1 command squared (props' thrust ∝ speed²).
    MIXER_THRUST_EXPO: f32 = f(106, "mixer.thrust_expo", 0.0, 1.0, 0.0),
    // loop (2xx)
    /// The gyro loop's rate.
    LOOP_RATE_HZ: u32 = c(200, "loop.rate_hz", LOOP_RATES, 1),
    // PID rate gains (3xx): roll, pitch, yaw × kp, ki, kd
    /// Roll rate PID: proportional gain (motor command per °/s of error).
    PID_ROLL_KP: f32 = f(300, "pid.roll.kp", 0.0, 1.0, 0.0030),
    /// Roll rate PID: integral gain.
    PID_ROLL_KI: f32 = f(301, "pid.roll.ki", 0.0, 1.0, 0.0050),
    /// Roll rate PID: derivative gain.
    PID_ROLL_KD: f32 = f(302, "pid.roll.kd", 0.0, 0.1, 0.00004),
    /// Pitch rate PID: proportional gain.
    PID_PITCH_KP: f32 = f(303, "pid.pitch.kp", 0.0, 1.0, 0.0030),
    /// Pitch rate PID: integral gain.
    PID_PITCH_KI: f32 = f(304, "pid.pitch.ki", 0.0, 1.0, 0.0050),
    /// Pitch rate PID: derivative gain.
    PID_PITCH_KD: f32 = f(305, "pid.pitch.kd", 0.0, 0.1, 0.00004),
    /// Yaw rate PID: proportional gain.
    PID_YAW_KP: f32 = f(306, "pid.yaw.kp", 0.0, 1.0, 0.0060),
    /// Yaw rate PID: integral gain.
    PID_YAW_KI: f32 = f(307, "pid.yaw.ki", 0.0, 1.0, 0.0100),
    /// Yaw rate PID: derivative gain.
    PID_YAW_KD: f32 = f(308, "pid.yaw.kd", 0.0, 0.1, 0.0),
    /// Attitude modes: commanded rate per unit of angle error (1/s).
    PID_ATTITUDE_KP: f32 = f(309, "pid.attitude.kp", 0.0, 20.0, 2.5),
    /// Rate modes: the rate full stick commands.
    RATE_MAX_DPS: f32 = f(310, "rate.max_dps", 30.0, 2_000.0, 720.0),
    /// Attitude modes: the tilt full stick commands.
    ATTITUDE_MAX_DEG: f32 = f(311, "attitude.max_deg", 5.0, 80.0, 45.0),
    // LQG model and costs (4xx)
    /// LQG model: ln of the roll axis's control authority β₁.
    LQG_LN_BETA1_ROLL: f32 = f(400, "lqg.ln_beta1.roll", 5.0, 14.0, 10.0),
    /// LQG model: ln of the pitch axis's control authority β₁.
    LQG_LN_BETA1_PITCH: f32 = f(401, "lqg.ln_beta1.pitch", 5.0, 14.0, 10.0),
    /// LQG model: ln of the yaw axis's control authority β₁.
    LQG_LN_BETA1_YAW: f32 = f(402, "lqg.ln_beta1.yaw", 3.0, 12.0, 7.0),
    /// LQG model: the motors' time constant τ.
    LQG_TAU_S: f32 = f(403, "lqg.tau_s", 0.005, 0.2, 0.03),
    // Frame-invariant LQR costs (control::design::FrameInvariantCosts: q1 angle, q2 rate,
    // q4 torque; each axis scales them by its own β1). Defaults: what autotune's
    // `lqg_costs` gives for τ = 30 ms (any β): 38 ms rate rise in the SITL, where Tau Labs'
    // absolute (10⁴, 4, 0.04) read as invariant gave a sluggish 216 ms. Key 407 (an unused
    // integral cost) is retired and must not be reused.
    /// LQR cost of rate error (frame-invariant, scaled by each axis's β₁).
    LQG_Q_RATE: f32 = f(404, "lqg.q_rate", 1e-6, 1e6, 1_000.0),
    /// LQR cost of torque (frame-invariant).
    LQG_Q_TORQUE: f32 = f(405, "lqg.q_torque", 1e-9, 1e3, 0.1),
    /// LQR cost of angle error (frame-invariant).
    LQG_Q_ATTITUDE: f32 = f(406, "lqg.q_attitude", 1e-3, 1e9, 480_000.0),
    // battery (5xx)
    /// Cells in series; 0 counts them from the voltage at power-up.
    BATTERY_CELLS: u32 = u(500, "battery.cells", 0, 6, 0),
    /// Cell voltage below which the battery warning sounds.
    BATTERY_CELL_WARNING_MV: u32 = u(501, "battery.cell_warning_mv", 2_800, 4_200, 3_500),
    /// Cell voltage below which the battery is critical (landing advised, arming refused).
    BATTERY_CELL_CRITICAL_MV: u32 = u(502, "battery.cell_critical_mv", 2_800, 4_200, 3_300),
    /// The voltage sense divider's ratio (battery volts per ADC volt).
    BATTERY_DIVIDER: f32 = f(503, "battery.divider", 1.0, 30.0, 2.0),
    /// The current sensor's output per ampere; 0: none fitted.
    BATTERY_CURRENT_MV_PER_A: f32 = f(504, "battery.current_mv_per_a", 0.0, 1_000.0, 50.0),
    // safety (6xx)
    // Key 600 (`failsafe.disarm_ms`, a fixed disarm time that could stop the motors in the
    // air) is retired and must not be reused: a failsafe now ends on detected touchdown.
    /// Failsafe: the descent rate held until touchdown is detected.
    FAILSAFE_DESCENT_MPS: f32 = f(601, "failsafe.descent_mps", 0.2, 3.0, 0.7),
    /// Disarm after this long armed at idle throttle.
    ARM_IDLE_DISARM_MS: u32 = u(602, "arm.idle_disarm_ms", 2_000, 120_000, 10_000),
    /// Flight mode of the mode switch's low position.
    MODE_SWITCH_LOW: u32 = c(603, "mode.switch_low", MODES, 2),
    /// Flight mode of the mode switch's middle position.
    MODE_SWITCH_MID: u32 = c(604, "mode.switch_mid", MODES, 0),
    /// Flight mode of the mode switch's high position.
    MODE_SWITCH_HIGH: u32 = c(605, "mode.switch_high", MODES, 1),
    // the bound link (7xx), written after an over-the-air bind; bind ID 0 = never bound
    /// The bound transmitter's ID (written by a bind; 0: never bound).
    LINK_BIND_ID: u32 = u(700, "link.bind_id", 0, u32::MAX, 0),
    /// The link's band (written by a bind).
    LINK_BAND: u32 = c(701, "link.band", BANDS, 0),
    /// The link's rate mode (written by a bind).
    LINK_RATE: u32 = c(702, "link.rate", RATES, 2),
    /// The uplink's channel format (written by a bind).
    LINK_CHANNELS: u32 = c(703, "link.channels", CHANNEL_FORMATS, 0),
    /// One downlink slot in this many (written by a bind).
    LINK_TELEMETRY_RATIO: u32 = u(704, "link.telemetry_ratio", 2, 128, 4),
    // Later safety settings, appended so the table index (the telemetry `SettingChange` id)
    // of every older row stays put.
    /// Whether arming is allowed with a critical battery.
    ARM_CRITICAL_BATTERY: u32 = c(606, "arm.critical_battery", ARM_ON_CRITICAL, 0),
    // The arm switch: 0 = stick gesture only; 1–16 = the channel number (5 = AUX1), "on"
    // while its pulse lies in arm.min_us…arm.max_us (CRSF: 988…2012 µs for −100…+100 %).
    /// The arm switch's channel (5 = AUX1); 0: the stick gesture only.
    ARM_CHANNEL: u32 = u(607, "arm.channel", 0, 16, 0),
    /// The arm channel reads "on" from this pulse length…
    ARM_MIN_US: u32 = u(608, "arm.min_us", 800, 2_200, 1_750),
    /// …up to this one.
    ARM_MAX_US: u32 = u(609, "arm.max_us", 800, 2_200, 2_100),
    // estimation (8xx). Factory: the complementary filter, as flown before the INS did.
    /// The attitude estimator.
    INS_MODE: u32 = c(800, "ins.mode", INS_MODES, 0),
    // The air protocol and the OpenLRSng bind data (7xx, appended): `link.olrs_*` are what
    // an OpenLRSng transmitter sent in its bind packet, with OpenLRSng's factory values
    // (`bindInitDefaults()`) as defaults; magic 0 = never bound over OpenLRSng. Packed so
    // the flash record grows little: `olrs_modem` is channel spacing (10 kHz units), modem
    // profile, flags and power code, one byte each from the low end; hop channels travel
    // four to a word, first in the low byte (`flight_core::pipeline` checks them all).
    /// The air protocol the receiver speaks.
    LINK_PROTOCOL: u32 = c(705, "link.protocol", PROTOCOLS, 0),
    /// OpenLRSng bind: the transmitter's magic (0: never bound over OpenLRSng).
    LINK_OLRS_MAGIC: u32 = u(706, "link.olrs_magic", 0, u32::MAX, 0),
    /// OpenLRSng bind: the base carrier frequency.
    LINK_OLRS_FREQUENCY_HZ: u32 = u(
        707,
        "link.olrs_frequency_hz",
        413_000_000,
        935_000_000,
        435_000_000,
    ),
    /// OpenLRSng bind: channel spacing, modem profile, flags and power, a byte each.
    LINK_OLRS_MODEM: u32 = u(708, "link.olrs_modem", 0, u32::MAX, 0x070A_0205),
    /// OpenLRSng bind: hop channels 1–4, first in the low byte.
    LINK_OLRS_HOPS_0: u32 = u(709, "link.olrs_hops_0", 0, u32::MAX, 0x2213_0A16),
    /// OpenLRSng bind: hop channels 5–8.
    LINK_OLRS_HOPS_1: u32 = u(710, "link.olrs_hops_1", 0, u32::MAX, 0x0000_2931),
    /// OpenLRSng bind: hop channels 9–12.
    LINK_OLRS_HOPS_2: u32 = u(711, "link.olrs_hops_2", 0, u32::MAX, 0),
    /// OpenLRSng bind: hop channels 13–16.
    LINK_OLRS_HOPS_3: u32 = u(712, "link.olrs_hops_3", 0, u32::MAX, 0),
    /// OpenLRSng bind: hop channels 17–20.
    LINK_OLRS_HOPS_4: u32 = u(713, "link.olrs_hops_4", 0, u32::MAX, 0),
    /// OpenLRSng bind: hop channels 21–24.
    LINK_OLRS_HOPS_5: u32 = u(714, "link.olrs_hops_5", 0, u32::MAX, 0),
    // Magnetometer calibration (`magcal save`; `flight_core::estimation::magcal`):
    // calibrated = matrix · (raw − offset), raw in the sensor's unit; the matrix symmetric.
    // Factory: none (zero offset, identity).
    /// Magnetometer calibration: x offset (sensor units).
    MAG_OFFSET_X: f32 = f(801, "mag.offset_x", -10_000.0, 10_000.0, 0.0),
    /// Magnetometer calibration: y offset (sensor units).
    MAG_OFFSET_Y: f32 = f(802, "mag.offset_y", -10_000.0, 10_000.0, 0.0),
    /// Magnetometer calibration: z offset (sensor units).
    MAG_OFFSET_Z: f32 = f(803, "mag.offset_z", -10_000.0, 10_000.0, 0.0),
    /// Magnetometer calibration: matrix element xx.
    MAG_XX: f32 = f(804, "mag.xx", -10.0, 10.0, 1.0),
    /// Magnetometer calibration: matrix element yy.
    MAG_YY: f32 = f(805, "mag.yy", -10.0, 10.0, 1.0),
    /// Magnetometer calibration: matrix element zz.
    MAG_ZZ: f32 = f(806, "mag.zz", -10.0, 10.0, 1.0),
    /// Magnetometer calibration: matrix element xy (= yx).
    MAG_XY: f32 = f(807, "mag.xy", -10.0, 10.0, 0.0),
    /// Magnetometer calibration: matrix element xz (= zx).
    MAG_XZ: f32 = f(808, "mag.xz", -10.0, 10.0, 0.0),
    /// Magnetometer calibration: matrix element yz (= zy).
    MAG_YZ: f32 = f(809, "mag.yz", -10.0, 10.0, 0.0),
    /// Magnetic declination at the flying field, east of true north (turns the heading).
    MAG_DECLINATION_DEG: f32 = f(810, "mag.declination_deg", -180.0, 180.0, 0.0),
    // Spec §12.1: only by this explicit setting; the module needs its own.
    /// 1 lets a bind without a key agreement through and its link run unauthenticated.
    LINK_UNAUTHENTICATED: u32 = u(715, "link.unauthenticated", 0, 1, 0),
    // The BrushedSparky's VTX (9xx, `flight_core::vtx`): applied at boot and while disarmed;
    // stored on the Sparky2 too (one table), unused there.
    /// VTX band of the pin-select module.
    VTX_BAND: u32 = c(900, "vtx.band", VTX_BANDS, 0),
    /// VTX channel 1–8 within the band.
    VTX_CHANNEL: u32 = u(901, "vtx.channel", 1, 8, 1),
    // The flight log (91x). Factory: `flight`, what the Sparky2's flash and the link take.
    /// Which topics the flight log records, at which rates.
    LOG_PROFILE: u32 = c(910, "log.profile", LOG_PROFILES, 2),
    // Dynamic transmit power (`telemetry::link::power`), appended: the flight side's
    // downlink power follows the link up to the radio's maximum.
    /// 1: the transmit power follows the link (`link::power`); 0: always the maximum.
    LINK_DYNAMIC_POWER: u32 = u(716, "link.dynamic_power", 0, 1, 1),
    ;
    // Handle arrays for the composite names, in the handles module.
    /// The rate PID gains, `[roll, pitch, yaw][kp, ki, kd]` (`pid.<axis>.<gain>`).
    pub const PID_GAINS: [[Handle<f32>; 3]; 3] = {
        [
            [PID_ROLL_KP, PID_ROLL_KI, PID_ROLL_KD],
            [PID_PITCH_KP, PID_PITCH_KI, PID_PITCH_KD],
            [PID_YAW_KP, PID_YAW_KI, PID_YAW_KD],
        ]
    };

    /// The LQG model's ln β₁, `[roll, pitch, yaw]` (`lqg.ln_beta1.<axis>`).
    pub const LQG_LN_BETA1: [Handle<f32>; 3] = {
        [LQG_LN_BETA1_ROLL, LQG_LN_BETA1_PITCH, LQG_LN_BETA1_YAW]
    };

    /// The OpenLRSng hop-channel words, four channels each (`link.olrs_hops_<n>`).
    pub const LINK_OLRS_HOPS: [Handle<u32>; 6] = {
        [
            LINK_OLRS_HOPS_0,
            LINK_OLRS_HOPS_1,
            LINK_OLRS_HOPS_2,
            LINK_OLRS_HOPS_3,
            LINK_OLRS_HOPS_4,
            LINK_OLRS_HOPS_5,
        ]
    };

    /// The magnetometer calibration: offset x, y, z, then the symmetric matrix's xx, yy, zz,
    /// xy, xz, yz (`mag.*`).
    pub const MAG_CALIBRATION: [Handle<f32>; 9] = {
        [
            MAG_OFFSET_X,
            MAG_OFFSET_Y,
            MAG_OFFSET_Z,
            MAG_XX,
            MAG_YY,
            MAG_ZZ,
            MAG_XY,
            MAG_XZ,
            MAG_YZ,
        ]
    };
}

/// Number of settings.
pub const COUNT: usize = PARAMS.len();
