//! The parameter table. Each parameter has a stable numeric key (what flash stores, so a
//! rename never loses a value), a dotted name (what the console shows), a kind with its
//! range, and a default. Values outside the range are refused, never clamped silently, and
//! so is any change after which the whole set would not run
//! ([`crate::pipeline::validate`]): a change leaves the set valid or untouched.

use core::marker::PhantomData;

use telemetry::link::LinkKey;

use super::decimal;
use super::handle::{Bits, Change, Handle, ParamType, Row, table};
use crate::pipeline::{InvalidSettings, validate};

/// A parameter's value.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Value {
    /// A real number.
    F32(f32),
    /// A whole number, or the index of a choice.
    U32(u32),
}

impl Value {
    /// The 32 bits stored in flash.
    pub fn to_bits(self) -> u32 {
        match self {
            Value::F32(v) => v.to_bits(),
            Value::U32(v) => v,
        }
    }
}

/// The names of an enumerated parameter.
pub type Choice = &'static [&'static str];

/// What a parameter holds, with its limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A real number in `min..=max`.
    F32 {
        /// Smallest allowed.
        min: f32,
        /// Largest allowed.
        max: f32,
    },
    /// A whole number in `min..=max`.
    U32 {
        /// Smallest allowed.
        min: u32,
        /// Largest allowed.
        max: u32,
    },
    /// One of named options (stored as its index).
    Choice(Choice),
}

/// One row of the table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Param {
    /// Stable flash key; never reuse one.
    pub key: u16,
    /// Console name.
    pub name: &'static str,
    /// Type and range.
    pub kind: Kind,
    /// Factory value.
    pub default: Value,
}

/// Why a value was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParamError {
    /// No parameter by that name or key.
    Unknown,
    /// Outside the parameter's range, or not one of its choices.
    OutOfRange,
    /// Not a number / not a choice name (or, for several pairs, a name without a value).
    Unparsable,
    /// The value is fine on its own, but the whole set would not run (nothing changed).
    Invalid(InvalidSettings),
}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ParamError::Unknown => "no such setting",
            ParamError::OutOfRange => "value out of range",
            ParamError::Unparsable => "cannot read that value",
            ParamError::Invalid(e) => return write!(f, "refused, the settings would not run: {e}"),
        })
    }
}

/// Most name/value pairs one `set` line may change together.
pub const MAX_PAIRS: usize = 8;

impl core::error::Error for ParamError {}

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

/// Output protocols, in `outputs::Protocol` order.
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
/// Link bands (`telemetry::link::Band`).
pub const BANDS: Choice = &["433", "868", "915"];
/// Link rate modes (`telemetry::link::RateMode`).
pub const RATES: Choice = &["l50", "m100", "f250", "f500", "f700"];
/// Uplink channel formats (`telemetry::channels::ChannelFormat`).
pub const CHANNEL_FORMATS: Choice = &["16", "8", "16-sticks"];
/// Air protocols (`link.protocol`): TauLink, OpenLRSng 3.8, OpenLRSng 3.9. OpenLRSng frames
/// carry no authentication.
pub const PROTOCOLS: Choice = &["taulink", "olrs38", "olrs39"];
/// Arming at a critical battery: refused (factory) or allowed.
pub const ARM_ON_CRITICAL: Choice = &["refuse", "allow"];
/// Gyro loop rates.
pub const LOOP_RATES: Choice = &["500", "1000"];
/// Estimators (`pipeline::EstimatorMode`): the complementary filter alone, the INS with
/// GPS, the INS without GPS (horizontal velocity held by a pseudo-measurement).
pub const INS_MODES: Choice = &["complementary", "ins", "ins_indoor"];
/// Flight-log profiles (`logging::Profile`): off, the telemetry channel's, the Sparky2
/// flash's, every sample (replay-grade).
pub const LOG_PROFILES: Choice = &["off", "link", "flight", "full"];

table! {
    // outputs (1xx)
    OUTPUT_PROTOCOL: u32 = c(100, "output.protocol", OUTPUT_PROTOCOLS, 0),
    OUTPUT_RATE_HZ: u32 = u(101, "output.rate_hz", 50, 64_000, 32_000),
    OUTPUT_MIN_US: u32 = u(102, "output.min_us", 500, 2_500, 1_000),
    OUTPUT_MAX_US: u32 = u(103, "output.max_us", 500, 2_500, 2_000),
    OUTPUT_IDLE: f32 = f(104, "output.idle", 0.0, 0.3, 0.05),
    MIXER_FRAME: u32 = c(105, "mixer.frame", FRAMES, 0),
    MIXER_THRUST_EXPO: f32 = f(106, "mixer.thrust_expo", 0.0, 1.0, 0.0),
    // loop (2xx)
    LOOP_RATE_HZ: u32 = c(200, "loop.rate_hz", LOOP_RATES, 1),
    // PID rate gains (3xx): roll, pitch, yaw × kp, ki, kd
    PID_ROLL_KP: f32 = f(300, "pid.roll.kp", 0.0, 1.0, 0.0030),
    PID_ROLL_KI: f32 = f(301, "pid.roll.ki", 0.0, 1.0, 0.0050),
    PID_ROLL_KD: f32 = f(302, "pid.roll.kd", 0.0, 0.1, 0.00004),
    PID_PITCH_KP: f32 = f(303, "pid.pitch.kp", 0.0, 1.0, 0.0030),
    PID_PITCH_KI: f32 = f(304, "pid.pitch.ki", 0.0, 1.0, 0.0050),
    PID_PITCH_KD: f32 = f(305, "pid.pitch.kd", 0.0, 0.1, 0.00004),
    PID_YAW_KP: f32 = f(306, "pid.yaw.kp", 0.0, 1.0, 0.0060),
    PID_YAW_KI: f32 = f(307, "pid.yaw.ki", 0.0, 1.0, 0.0100),
    PID_YAW_KD: f32 = f(308, "pid.yaw.kd", 0.0, 0.1, 0.0),
    PID_ATTITUDE_KP: f32 = f(309, "pid.attitude.kp", 0.0, 20.0, 2.5),
    RATE_MAX_DPS: f32 = f(310, "rate.max_dps", 30.0, 2_000.0, 720.0),
    ATTITUDE_MAX_DEG: f32 = f(311, "attitude.max_deg", 5.0, 80.0, 45.0),
    // LQG model and costs (4xx)
    LQG_LN_BETA1_ROLL: f32 = f(400, "lqg.ln_beta1.roll", 5.0, 14.0, 10.0),
    LQG_LN_BETA1_PITCH: f32 = f(401, "lqg.ln_beta1.pitch", 5.0, 14.0, 10.0),
    LQG_LN_BETA1_YAW: f32 = f(402, "lqg.ln_beta1.yaw", 3.0, 12.0, 7.0),
    LQG_TAU_S: f32 = f(403, "lqg.tau_s", 0.005, 0.2, 0.03),
    // Frame-invariant LQR costs (control::design::FrameInvariantCosts: q1 angle, q2 rate,
    // q4 torque; each axis scales them by its own β1). Defaults: what autotune's
    // `lqg_costs` gives for τ = 30 ms (any β): 38 ms rate rise in the SITL, where Tau Labs'
    // absolute (10⁴, 4, 0.04) read as invariant gave a sluggish 216 ms. Key 407 (an unused
    // integral cost) is retired and must not be reused.
    LQG_Q_RATE: f32 = f(404, "lqg.q_rate", 1e-6, 1e6, 1_000.0),
    LQG_Q_TORQUE: f32 = f(405, "lqg.q_torque", 1e-9, 1e3, 0.1),
    LQG_Q_ATTITUDE: f32 = f(406, "lqg.q_attitude", 1e-3, 1e9, 480_000.0),
    // battery (5xx)
    BATTERY_CELLS: u32 = u(500, "battery.cells", 0, 6, 0),
    BATTERY_CELL_WARNING_MV: u32 = u(501, "battery.cell_warning_mv", 2_800, 4_200, 3_500),
    BATTERY_CELL_CRITICAL_MV: u32 = u(502, "battery.cell_critical_mv", 2_800, 4_200, 3_300),
    BATTERY_DIVIDER: f32 = f(503, "battery.divider", 1.0, 30.0, 2.0),
    BATTERY_CURRENT_MV_PER_A: f32 = f(504, "battery.current_mv_per_a", 0.0, 1_000.0, 50.0),
    // safety (6xx)
    // Key 600 (`failsafe.disarm_ms`, a fixed disarm time that could stop the motors in the
    // air) is retired and must not be reused: a failsafe now ends on detected touchdown.
    FAILSAFE_DESCENT_MPS: f32 = f(601, "failsafe.descent_mps", 0.2, 3.0, 0.7),
    ARM_IDLE_DISARM_MS: u32 = u(602, "arm.idle_disarm_ms", 2_000, 120_000, 10_000),
    MODE_SWITCH_LOW: u32 = c(603, "mode.switch_low", MODES, 2),
    MODE_SWITCH_MID: u32 = c(604, "mode.switch_mid", MODES, 0),
    MODE_SWITCH_HIGH: u32 = c(605, "mode.switch_high", MODES, 1),
    // the bound link (7xx), written after an over-the-air bind; bind ID 0 = never bound
    LINK_BIND_ID: u32 = u(700, "link.bind_id", 0, u32::MAX, 0),
    LINK_BAND: u32 = c(701, "link.band", BANDS, 0),
    LINK_RATE: u32 = c(702, "link.rate", RATES, 2),
    LINK_CHANNELS: u32 = c(703, "link.channels", CHANNEL_FORMATS, 0),
    LINK_TELEMETRY_RATIO: u32 = u(704, "link.telemetry_ratio", 2, 128, 4),
    // Later safety settings, appended so the table index (the telemetry `SettingChange` id)
    // of every older row stays put.
    ARM_CRITICAL_BATTERY: u32 = c(606, "arm.critical_battery", ARM_ON_CRITICAL, 0),
    // The arm switch: 0 = stick gesture only; 1–16 = the channel number (5 = AUX1), "on"
    // while its pulse lies in arm.min_us…arm.max_us (CRSF: 988…2012 µs for −100…+100 %).
    ARM_CHANNEL: u32 = u(607, "arm.channel", 0, 16, 0),
    ARM_MIN_US: u32 = u(608, "arm.min_us", 800, 2_200, 1_750),
    ARM_MAX_US: u32 = u(609, "arm.max_us", 800, 2_200, 2_100),
    // estimation (8xx). Factory: the complementary filter, as flown before the INS did.
    INS_MODE: u32 = c(800, "ins.mode", INS_MODES, 0),
    // The air protocol and the OpenLRSng bind data (7xx, appended): `link.olrs_*` are what
    // an OpenLRSng transmitter sent in its bind packet, with OpenLRSng's factory values
    // (`bindInitDefaults()`) as defaults; magic 0 = never bound over OpenLRSng. Packed so
    // the flash record grows little: `olrs_modem` is channel spacing (10 kHz units), modem
    // profile, flags and power code, one byte each from the low end; hop channels travel
    // four to a word, first in the low byte (`pipeline::stored_openlrs` checks them all).
    LINK_PROTOCOL: u32 = c(705, "link.protocol", PROTOCOLS, 0),
    LINK_OLRS_MAGIC: u32 = u(706, "link.olrs_magic", 0, u32::MAX, 0),
    LINK_OLRS_FREQUENCY_HZ: u32 = u(
        707,
        "link.olrs_frequency_hz",
        413_000_000,
        935_000_000,
        435_000_000,
    ),
    LINK_OLRS_MODEM: u32 = u(708, "link.olrs_modem", 0, u32::MAX, 0x070A_0205),
    LINK_OLRS_HOPS_0: u32 = u(709, "link.olrs_hops_0", 0, u32::MAX, 0x2213_0A16),
    LINK_OLRS_HOPS_1: u32 = u(710, "link.olrs_hops_1", 0, u32::MAX, 0x0000_2931),
    LINK_OLRS_HOPS_2: u32 = u(711, "link.olrs_hops_2", 0, u32::MAX, 0),
    LINK_OLRS_HOPS_3: u32 = u(712, "link.olrs_hops_3", 0, u32::MAX, 0),
    LINK_OLRS_HOPS_4: u32 = u(713, "link.olrs_hops_4", 0, u32::MAX, 0),
    LINK_OLRS_HOPS_5: u32 = u(714, "link.olrs_hops_5", 0, u32::MAX, 0),
    // Magnetometer calibration (`magcal save`; `estimation::magcal`): calibrated =
    // matrix · (raw − offset), raw in the sensor's unit; the matrix symmetric. Factory: none
    // (zero offset, identity).
    MAG_OFFSET_X: f32 = f(801, "mag.offset_x", -10_000.0, 10_000.0, 0.0),
    MAG_OFFSET_Y: f32 = f(802, "mag.offset_y", -10_000.0, 10_000.0, 0.0),
    MAG_OFFSET_Z: f32 = f(803, "mag.offset_z", -10_000.0, 10_000.0, 0.0),
    MAG_XX: f32 = f(804, "mag.xx", -10.0, 10.0, 1.0),
    MAG_YY: f32 = f(805, "mag.yy", -10.0, 10.0, 1.0),
    MAG_ZZ: f32 = f(806, "mag.zz", -10.0, 10.0, 1.0),
    MAG_XY: f32 = f(807, "mag.xy", -10.0, 10.0, 0.0),
    MAG_XZ: f32 = f(808, "mag.xz", -10.0, 10.0, 0.0),
    MAG_YZ: f32 = f(809, "mag.yz", -10.0, 10.0, 0.0),
    // Magnetic declination at the flying field, degrees east of true north: the heading the
    // estimators take from the magnetometer is turned by it (`estimation::align`).
    MAG_DECLINATION_DEG: f32 = f(810, "mag.declination_deg", -180.0, 180.0, 0.0),
    // 1 lets a bind without a key agreement through and the link it stores run
    // unauthenticated (spec §12.1: only by this explicit setting; the module needs its own).
    LINK_UNAUTHENTICATED: u32 = u(715, "link.unauthenticated", 0, 1, 0),
    // The flight log (9xx): which topics at which rates (`logging::Profile`). Factory:
    // `flight`, what the Sparky2's flash and the link stream take.
    LOG_PROFILE: u32 = c(900, "log.profile", LOG_PROFILES, 2),
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

/// Number of parameters.
pub const COUNT: usize = PARAMS.len();

/// Looks a parameter up by name.
pub fn find(name: &str) -> Option<(usize, &'static Param)> {
    PARAMS.iter().enumerate().find(|(_, p)| p.name == name)
}

impl Param {
    /// Checks `value` against the kind and range.
    pub fn check(&self, value: Value) -> Result<Value, ParamError> {
        match (self.kind, value) {
            (Kind::F32 { min, max }, Value::F32(v))
                if v.is_finite() && (min..=max).contains(&v) =>
            {
                Ok(value)
            }
            (Kind::U32 { min, max }, Value::U32(v)) if (min..=max).contains(&v) => Ok(value),
            (Kind::Choice(names), Value::U32(v)) if (v as usize) < names.len() => Ok(value),
            _ => Err(ParamError::OutOfRange),
        }
    }

    /// Reads a value from console text: a number, or a choice's name.
    pub fn parse(&self, text: &str) -> Result<Value, ParamError> {
        let value = match self.kind {
            Kind::F32 { .. } => Value::F32(decimal::parse(text).ok_or(ParamError::Unparsable)?),
            Kind::U32 { .. } => Value::U32(text.parse().map_err(|_| ParamError::Unparsable)?),
            Kind::Choice(names) => {
                let i = names
                    .iter()
                    .position(|n| *n == text)
                    .ok_or(ParamError::Unparsable)?;
                Value::U32(i as u32)
            }
        };
        self.check(value)
    }

    /// Rebuilds a value from its stored bits.
    pub fn from_bits(&self, bits: u32) -> Result<Value, ParamError> {
        let value = match self.kind {
            Kind::F32 { .. } => Value::F32(f32::from_bits(bits)),
            Kind::U32 { .. } | Kind::Choice(_) => Value::U32(bits),
        };
        self.check(value)
    }
}

/// The current value of every parameter, and the link key.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Each parameter's stored bits in table order; its row's kind says how to read them
    /// (a [`Handle`] reads them as its type).
    values: Bits,
    /// The link key derived from the binding phrase (spec §12), outside the table: it is
    /// no parameter a `list`, `get` or `SettingChange` can read, only the console's `phrase`
    /// sets it. `None`: no phrase, the link runs unauthenticated.
    link_key: Option<LinkKey>,
}

impl Default for Settings {
    fn default() -> Self {
        let mut values = [0; COUNT];
        for (v, p) in values.iter_mut().zip(PARAMS) {
            *v = p.default.to_bits();
        }
        Self {
            values,
            link_key: None,
        }
    }
}

/// A row's value from its stored bits (the kind decides which type they are).
fn value_of(param: &Param, bits: u32) -> Value {
    match param.kind {
        Kind::F32 { .. } => Value::F32(f32::from_bits(bits)),
        Kind::U32 { .. } | Kind::Choice(_) => Value::U32(bits),
    }
}

impl Settings {
    /// The link key (from the binding phrase), if one is set.
    pub fn link_key(&self) -> Option<LinkKey> {
        self.link_key
    }

    /// Sets or clears the link key (the console's `phrase`; the key only, never the
    /// phrase, is kept).
    pub fn set_link_key(&mut self, key: Option<LinkKey>) {
        self.link_key = key;
    }

    /// A parameter's value, typed by its handle (`settings.get(handles::RATE_MAX_DPS)`).
    pub fn get<T: ParamType>(&self, handle: Handle<T>) -> T {
        T::from_bits((handle.read)(&self.values))
    }

    /// Value by console name (the console, telemetry and the phone; code uses [`Self::get`]).
    pub fn by_name(&self, name: &str) -> Option<Value> {
        let (i, p) = find(name)?;
        self.values.get(i).map(|&bits| value_of(p, bits))
    }

    /// Changes a value, given by console name, after checking it and the whole set it makes.
    pub fn set(&mut self, name: &str, value: Value) -> Result<(), ParamError> {
        self.set_many(&[(name, value)])
    }

    /// Changes one value, named by its handle (see [`Self::apply`]).
    pub fn put<T: ParamType>(&mut self, handle: Handle<T>, value: T) -> Result<(), ParamError> {
        self.apply(&[handle.to(value)])
    }

    /// Changes several values given by console name at once (see [`Self::apply`]; code
    /// names them by handle and calls `apply`).
    pub fn set_many(&mut self, changes: &[(&str, Value)]) -> Result<(), ParamError> {
        let mut typed: heapless::Vec<Change, COUNT> = heapless::Vec::new();
        for &(name, value) in changes {
            let (index, _) = find(name).ok_or(ParamError::Unknown)?;
            typed
                .push(Change { index, value })
                .map_err(|_| ParamError::Unparsable)?;
        }
        self.apply(&typed)
    }

    /// Changes several values at once (`handle.to(value)` each): each is range-checked, then
    /// the whole resulting set is validated; on any error nothing changes. Use it for
    /// changes that are only valid together (PWM and its rate, a bind's five `link.*` values).
    pub fn apply(&mut self, changes: &[Change]) -> Result<(), ParamError> {
        let mut candidate = self.clone();
        for change in changes {
            let p = PARAMS.get(change.index).ok_or(ParamError::Unknown)?;
            let checked = p.check(change.value)?;
            let slot = candidate
                .values
                .get_mut(change.index)
                .ok_or(ParamError::Unknown)?;
            *slot = checked.to_bits();
        }
        candidate.check().map_err(ParamError::Invalid)?;
        *self = candidate;
        Ok(())
    }

    /// Changes a value given as console text.
    pub fn set_text(&mut self, name: &str, text: &str) -> Result<(), ParamError> {
        let (_, p) = find(name).ok_or(ParamError::Unknown)?;
        let value = p.parse(text)?;
        self.set(name, value)
    }

    /// Changes up to [`MAX_PAIRS`] values given as console text, `NAME VALUE NAME VALUE …`,
    /// together (see [`Settings::apply`]).
    pub fn set_text_pairs(&mut self, text: &str) -> Result<(), ParamError> {
        let mut changes: heapless::Vec<Change, MAX_PAIRS> = heapless::Vec::new();
        let mut words = text.split_ascii_whitespace();
        while let Some(name) = words.next() {
            let value_text = words.next().ok_or(ParamError::Unparsable)?;
            let (index, p) = find(name).ok_or(ParamError::Unknown)?;
            let value = p.parse(value_text)?;
            changes
                .push(Change { index, value })
                .map_err(|_| ParamError::Unparsable)?;
        }
        self.apply(&changes)
    }

    /// Whether the whole set can run (every cross-setting rule).
    pub fn check(&self) -> Result<(), InvalidSettings> {
        validate(self).map(|_| ())
    }

    /// This set if it can run, else the factory set and why this one was refused (for the
    /// console and telemetry). What boot does with a stored set.
    pub fn or_defaults(self) -> (Self, Option<InvalidSettings>) {
        match self.check() {
            Ok(()) => (self, None),
            Err(e) => (Self::default(), Some(e)),
        }
    }

    /// (parameter, value) pairs in table order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static Param, Value)> + '_ {
        PARAMS
            .iter()
            .zip(self.values.iter())
            .map(|(p, &bits)| (p, value_of(p, bits)))
    }

    pub(crate) fn set_by_key(&mut self, key: u16, bits: u32) -> Result<(), ParamError> {
        let i = PARAMS
            .iter()
            .position(|p| p.key == key)
            .ok_or(ParamError::Unknown)?;
        let p = PARAMS.get(i).ok_or(ParamError::Unknown)?;
        let value = p.from_bits(bits)?;
        let slot = self.values.get_mut(i).ok_or(ParamError::Unknown)?;
        *slot = value.to_bits();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_consistent() {
        for (i, p) in PARAMS.iter().enumerate() {
            assert_eq!(
                p.check(p.default),
                Ok(p.default),
                "{} default out of range",
                p.name
            );
            for q in &PARAMS[i + 1..] {
                assert_ne!(p.key, q.key, "duplicate key");
                assert_ne!(p.name, q.name, "duplicate name");
            }
        }
    }

    #[test]
    fn every_handle_names_a_row_of_its_type() {
        let rows = handle_rows();
        assert_eq!(rows.len(), COUNT, "one handle per row");
        for (i, (ident, index, fits)) in rows.into_iter().enumerate() {
            assert_eq!(index, i, "{ident} is not in table order");
            let p = &PARAMS[index];
            assert_eq!(
                ident,
                p.name.to_uppercase().replace('.', "_"),
                "{ident} names another row"
            );
            assert!(fits, "{ident}'s type does not match {}'s kind", p.name);
        }
        let s = Settings::default();
        assert_eq!(s.get(handles::OUTPUT_RATE_HZ), 32_000);
        assert_eq!(s.get(handles::RATE_MAX_DPS), 720.0);
        assert_eq!(
            handles::PID_GAINS[2][0].param().map(|p| p.name),
            Some("pid.yaw.kp")
        );
        assert_eq!(
            handles::LQG_LN_BETA1[1].param().map(|p| p.name),
            Some("lqg.ln_beta1.pitch")
        );
        assert_eq!(
            handles::LINK_OLRS_HOPS[5].param().map(|p| p.name),
            Some("link.olrs_hops_5")
        );
        assert_eq!(
            handles::MAG_CALIBRATION[6].param().map(|p| p.name),
            Some("mag.xy")
        );
    }

    #[test]
    fn set_checks_ranges_and_choices() {
        let mut s = Settings::default();
        assert_eq!(s.get(handles::OUTPUT_RATE_HZ), 32_000);
        s.set_text("output.protocol", "oneshot125").unwrap();
        assert_eq!(s.get(handles::OUTPUT_PROTOCOL), 2);
        assert_eq!(
            s.set_text("output.protocol", "dshot"),
            Err(ParamError::Unparsable)
        );
        assert_eq!(
            s.set_text("pid.roll.kp", "2.5"),
            Err(ParamError::OutOfRange)
        );
        assert_eq!(
            s.set_text("pid.roll.kp", "NaN"),
            Err(ParamError::OutOfRange)
        );
        s.set_text("pid.roll.kp", "0.004").unwrap();
        assert_eq!(s.get(handles::PID_ROLL_KP), 0.004);
        assert_eq!(s.set_text("no.such", "1"), Err(ParamError::Unknown));
        assert_eq!(
            s.set("battery.cells", Value::F32(1.0)),
            Err(ParamError::OutOfRange),
            "wrong kind"
        );
    }
}
