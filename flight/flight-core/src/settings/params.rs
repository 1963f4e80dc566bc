//! The parameter table. Each parameter has a stable numeric key (what flash stores, so a
//! rename never loses a value), a dotted name (what the console shows), a kind with its
//! range, and a default. Values outside the range are refused, never clamped silently, and
//! so is any change after which the whole set would not run
//! ([`crate::pipeline::validate`]): a change leaves the set valid or untouched.

use telemetry::link::LinkKey;

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

const fn f(key: u16, name: &'static str, min: f32, max: f32, default: f32) -> Param {
    Param {
        key,
        name,
        kind: Kind::F32 { min, max },
        default: Value::F32(default),
    }
}

const fn u(key: u16, name: &'static str, min: u32, max: u32, default: u32) -> Param {
    Param {
        key,
        name,
        kind: Kind::U32 { min, max },
        default: Value::U32(default),
    }
}

const fn c(key: u16, name: &'static str, choice: Choice, default: u32) -> Param {
    Param {
        key,
        name,
        kind: Kind::Choice(choice),
        default: Value::U32(default),
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

/// Every parameter. Keys are grouped by hundreds per subsystem.
pub const PARAMS: &[Param] = &[
    // outputs (1xx)
    c(100, "output.protocol", OUTPUT_PROTOCOLS, 0),
    u(101, "output.rate_hz", 50, 64_000, 32_000),
    u(102, "output.min_us", 500, 2_500, 1_000),
    u(103, "output.max_us", 500, 2_500, 2_000),
    f(104, "output.idle", 0.0, 0.3, 0.05),
    c(105, "mixer.frame", FRAMES, 0),
    f(106, "mixer.thrust_expo", 0.0, 1.0, 0.0),
    // loop (2xx)
    c(200, "loop.rate_hz", LOOP_RATES, 1),
    // PID rate gains (3xx): roll, pitch, yaw × kp, ki, kd
    f(300, "pid.roll.kp", 0.0, 1.0, 0.0030),
    f(301, "pid.roll.ki", 0.0, 1.0, 0.0050),
    f(302, "pid.roll.kd", 0.0, 0.1, 0.00004),
    f(303, "pid.pitch.kp", 0.0, 1.0, 0.0030),
    f(304, "pid.pitch.ki", 0.0, 1.0, 0.0050),
    f(305, "pid.pitch.kd", 0.0, 0.1, 0.00004),
    f(306, "pid.yaw.kp", 0.0, 1.0, 0.0060),
    f(307, "pid.yaw.ki", 0.0, 1.0, 0.0100),
    f(308, "pid.yaw.kd", 0.0, 0.1, 0.0),
    f(309, "pid.attitude.kp", 0.0, 20.0, 2.5),
    f(310, "rate.max_dps", 30.0, 2_000.0, 720.0),
    f(311, "attitude.max_deg", 5.0, 80.0, 45.0),
    // LQG model and costs (4xx)
    f(400, "lqg.ln_beta1.roll", 5.0, 14.0, 10.0),
    f(401, "lqg.ln_beta1.pitch", 5.0, 14.0, 10.0),
    f(402, "lqg.ln_beta1.yaw", 3.0, 12.0, 7.0),
    f(403, "lqg.tau_s", 0.005, 0.2, 0.03),
    // Frame-invariant LQR costs (control::design::FrameInvariantCosts: q1 angle, q2 rate,
    // q4 torque; each axis scales them by its own β1). Defaults: what autotune's
    // `lqg_costs` gives for τ = 30 ms (any β): 38 ms rate rise in the SITL, where Tau Labs'
    // absolute (10⁴, 4, 0.04) read as invariant gave a sluggish 216 ms. Key 407 (an unused
    // integral cost) is retired and must not be reused.
    f(404, "lqg.q_rate", 1e-6, 1e6, 1_000.0),
    f(405, "lqg.q_torque", 1e-9, 1e3, 0.1),
    f(406, "lqg.q_attitude", 1e-3, 1e9, 480_000.0),
    // battery (5xx)
    u(500, "battery.cells", 0, 6, 0),
    u(501, "battery.cell_warning_mv", 2_800, 4_200, 3_500),
    u(502, "battery.cell_critical_mv", 2_800, 4_200, 3_300),
    f(503, "battery.divider", 1.0, 30.0, 2.0),
    f(504, "battery.current_mv_per_a", 0.0, 1_000.0, 50.0),
    // safety (6xx)
    // Key 600 (`failsafe.disarm_ms`, a fixed disarm time that could stop the motors in the
    // air) is retired and must not be reused: a failsafe now ends on detected touchdown.
    f(601, "failsafe.descent_mps", 0.2, 3.0, 0.7),
    u(602, "arm.idle_disarm_ms", 2_000, 120_000, 10_000),
    c(603, "mode.switch_low", MODES, 2),
    c(604, "mode.switch_mid", MODES, 0),
    c(605, "mode.switch_high", MODES, 1),
    // the bound link (7xx), written after an over-the-air bind; bind ID 0 = never bound
    u(700, "link.bind_id", 0, u32::MAX, 0),
    c(701, "link.band", BANDS, 0),
    c(702, "link.rate", RATES, 2),
    c(703, "link.channels", CHANNEL_FORMATS, 0),
    u(704, "link.telemetry_ratio", 2, 128, 4),
    // Later safety settings, appended so the table index (the telemetry `SettingChange` id)
    // of every older row stays put.
    c(606, "arm.critical_battery", ARM_ON_CRITICAL, 0),
    // The arm switch: 0 = stick gesture only; 1–16 = the channel number (5 = AUX1), "on"
    // while its pulse lies in arm.min_us…arm.max_us (CRSF: 988…2012 µs for −100…+100 %).
    u(607, "arm.channel", 0, 16, 0),
    u(608, "arm.min_us", 800, 2_200, 1_750),
    u(609, "arm.max_us", 800, 2_200, 2_100),
    // estimation (8xx). Factory: the complementary filter, as flown before the INS did.
    c(800, "ins.mode", INS_MODES, 0),
    // The air protocol and the OpenLRSng bind data (7xx, appended): `link.olrs_*` are what
    // an OpenLRSng transmitter sent in its bind packet, with OpenLRSng's factory values
    // (`bindInitDefaults()`) as defaults; magic 0 = never bound over OpenLRSng. Packed so
    // the flash record grows little: `olrs_modem` is channel spacing (10 kHz units), modem
    // profile, flags and power code, one byte each from the low end; hop channels travel
    // four to a word, first in the low byte (`pipeline::stored_openlrs` checks them all).
    c(705, "link.protocol", PROTOCOLS, 0),
    u(706, "link.olrs_magic", 0, u32::MAX, 0),
    u(
        707,
        "link.olrs_frequency_hz",
        413_000_000,
        935_000_000,
        435_000_000,
    ),
    u(708, "link.olrs_modem", 0, u32::MAX, 0x070A_0205),
    u(709, "link.olrs_hops_0", 0, u32::MAX, 0x2213_0A16),
    u(710, "link.olrs_hops_1", 0, u32::MAX, 0x0000_2931),
    u(711, "link.olrs_hops_2", 0, u32::MAX, 0),
    u(712, "link.olrs_hops_3", 0, u32::MAX, 0),
    u(713, "link.olrs_hops_4", 0, u32::MAX, 0),
    u(714, "link.olrs_hops_5", 0, u32::MAX, 0),
    // Magnetometer calibration (`magcal save`; `estimation::magcal`): calibrated =
    // matrix · (raw − offset), raw in the sensor's unit; the matrix symmetric. Factory: none
    // (zero offset, identity).
    f(801, "mag.offset_x", -10_000.0, 10_000.0, 0.0),
    f(802, "mag.offset_y", -10_000.0, 10_000.0, 0.0),
    f(803, "mag.offset_z", -10_000.0, 10_000.0, 0.0),
    f(804, "mag.xx", -10.0, 10.0, 1.0),
    f(805, "mag.yy", -10.0, 10.0, 1.0),
    f(806, "mag.zz", -10.0, 10.0, 1.0),
    f(807, "mag.xy", -10.0, 10.0, 0.0),
    f(808, "mag.xz", -10.0, 10.0, 0.0),
    f(809, "mag.yz", -10.0, 10.0, 0.0),
];

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
            Kind::F32 { .. } => Value::F32(text.parse().map_err(|_| ParamError::Unparsable)?),
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
    values: [Value; COUNT],
    /// The link key derived from the binding phrase (spec §12), outside the table: it is
    /// no parameter a `list`, `get` or `SettingChange` can read, only the console's `phrase`
    /// sets it. `None`: no phrase, the link runs unauthenticated.
    link_key: Option<LinkKey>,
}

impl Default for Settings {
    fn default() -> Self {
        let mut values = [Value::U32(0); COUNT];
        for (v, p) in values.iter_mut().zip(PARAMS) {
            *v = p.default;
        }
        Self {
            values,
            link_key: None,
        }
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

    /// Value by name.
    pub fn get(&self, name: &str) -> Option<Value> {
        let (i, _) = find(name)?;
        self.values.get(i).copied()
    }

    /// A real-number parameter (its default if the name is wrong, which a test catches).
    pub fn f32(&self, name: &str) -> f32 {
        match self.get(name) {
            Some(Value::F32(v)) => v,
            _ => 0.0,
        }
    }

    /// A whole-number or choice parameter.
    pub fn u32(&self, name: &str) -> u32 {
        match self.get(name) {
            Some(Value::U32(v)) => v,
            _ => 0,
        }
    }

    /// Changes a value after checking it and the whole set it makes.
    pub fn set(&mut self, name: &str, value: Value) -> Result<(), ParamError> {
        self.set_many(&[(name, value)])
    }

    /// Changes several values at once: each is range-checked, then the whole resulting set
    /// is validated; on any error nothing changes. Use it for changes that are only valid
    /// together (PWM and its rate, a bind's five `link.*` values).
    pub fn set_many(&mut self, changes: &[(&str, Value)]) -> Result<(), ParamError> {
        let mut candidate = self.clone();
        for &(name, value) in changes {
            let (i, p) = find(name).ok_or(ParamError::Unknown)?;
            let checked = p.check(value)?;
            let slot = candidate.values.get_mut(i).ok_or(ParamError::Unknown)?;
            *slot = checked;
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
    /// together (see [`Settings::set_many`]).
    pub fn set_text_pairs(&mut self, text: &str) -> Result<(), ParamError> {
        let mut changes: heapless::Vec<(&str, Value), MAX_PAIRS> = heapless::Vec::new();
        let mut words = text.split_ascii_whitespace();
        while let Some(name) = words.next() {
            let value_text = words.next().ok_or(ParamError::Unparsable)?;
            let (_, p) = find(name).ok_or(ParamError::Unknown)?;
            let value = p.parse(value_text)?;
            changes
                .push((p.name, value))
                .map_err(|_| ParamError::Unparsable)?;
        }
        self.set_many(&changes)
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
        PARAMS.iter().zip(self.values.iter().copied())
    }

    pub(crate) fn set_by_key(&mut self, key: u16, bits: u32) -> Result<(), ParamError> {
        let i = PARAMS
            .iter()
            .position(|p| p.key == key)
            .ok_or(ParamError::Unknown)?;
        let p = PARAMS.get(i).ok_or(ParamError::Unknown)?;
        let value = p.from_bits(bits)?;
        let slot = self.values.get_mut(i).ok_or(ParamError::Unknown)?;
        *slot = value;
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
    fn set_checks_ranges_and_choices() {
        let mut s = Settings::default();
        assert_eq!(s.u32("output.rate_hz"), 32_000);
        s.set_text("output.protocol", "oneshot125").unwrap();
        assert_eq!(s.u32("output.protocol"), 2);
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
        assert_eq!(s.f32("pid.roll.kp"), 0.004);
        assert_eq!(s.set_text("no.such", "1"), Err(ParamError::Unknown));
        assert_eq!(
            s.set("battery.cells", Value::F32(1.0)),
            Err(ParamError::OutOfRange),
            "wrong kind"
        );
    }
}
