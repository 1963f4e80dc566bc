//! Whole-set settings validation: every rule that spans more than one parameter, checked
//! the way the consumers will apply the set — the flight setup ([`from_settings`]), the
//! output protocol on the real motor timers, and the bound link's parameters. A change that
//! fails is refused before it reaches the set (`Settings::set`), and a stored set that fails
//! at boot is replaced by the defaults, so the board never boots into settings its motor or
//! link task refuses (which used to reset it forever).

use telemetry::frame::valid_telemetry_ratio;

use super::link::{openlrs_valid, stored_link};
use super::setup::{FlightSetup, SetupError, from_settings};
use crate::board::MOTOR_TIMER_CLOCKS;
use crate::outputs::OutputError;
use crate::settings::{Settings, handles};

/// Why a settings set cannot run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InvalidSettings {
    /// The flight setup refuses it (frame, model, battery thresholds, arm switch, …).
    Setup(SetupError),
    /// The motor timers cannot run the output protocol (e.g. PWM at 32 kHz, brushed at
    /// 400 Hz, PWM min ≥ max).
    Output(OutputError),
    /// The bound link's parameters are not a valid link (e.g. a telemetry ratio that is not
    /// a power of two).
    Link,
}

impl core::fmt::Display for InvalidSettings {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            InvalidSettings::Setup(e) => write!(f, "{e}"),
            InvalidSettings::Output(e) => write!(f, "outputs: {e}"),
            InvalidSettings::Link => f.write_str(
                "link: telemetry ratio must be 2, 4, … 128, OpenLRSng bind data in band",
            ),
        }
    }
}

impl core::error::Error for InvalidSettings {}

/// Checks the whole set; on success returns what it derived.
pub fn validate(s: &Settings) -> Result<FlightSetup, InvalidSettings> {
    let setup = from_settings(s).map_err(InvalidSettings::Setup)?;
    for timer in MOTOR_TIMER_CLOCKS {
        setup
            .protocol
            .timing(timer)
            .map_err(InvalidSettings::Output)?;
    }
    // The ratio is checked even before a bind: the module side would refuse it on the air.
    let ratio = u8::try_from(s.get(handles::LINK_TELEMETRY_RATIO)).unwrap_or(0);
    if !valid_telemetry_ratio(ratio) {
        return Err(InvalidSettings::Link);
    }
    if s.get(handles::LINK_BIND_ID) != 0 && stored_link(s).is_none() {
        return Err(InvalidSettings::Link);
    }
    if !openlrs_valid(s) {
        return Err(InvalidSettings::Link);
    }
    Ok(setup)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::{ParamError, Value};

    #[test]
    fn the_defaults_are_valid() {
        assert!(validate(&Settings::default()).is_ok());
    }

    #[test]
    fn settings_that_cannot_run_are_refused_and_leave_the_set_unchanged() {
        let defaults = Settings::default();
        let refused = |name: &str, text: &str| {
            let mut s = Settings::default();
            let e = s.set_text(name, text).unwrap_err();
            assert_eq!(s, defaults, "{name} {text} changed the set");
            e
        };
        // PWM at the default 32 kHz rate.
        assert_eq!(
            refused("output.protocol", "pwm"),
            ParamError::Invalid(InvalidSettings::Output(OutputError::RateOutOfRange))
        );
        // Brushed at 400 Hz.
        assert_eq!(
            refused("output.rate_hz", "400"),
            ParamError::Invalid(InvalidSettings::Output(OutputError::RateOutOfRange))
        );
        assert_eq!(
            refused("link.telemetry_ratio", "3"),
            ParamError::Invalid(InvalidSettings::Link)
        );
        assert_eq!(
            refused("battery.cell_critical_mv", "3600"),
            ParamError::Invalid(InvalidSettings::Setup(SetupError::BatteryThresholds))
        );
        assert_eq!(
            refused("arm.channel", "3"),
            ParamError::Invalid(InvalidSettings::Setup(SetupError::ArmChannelInUse))
        );
        // PWM with min > max, reached through a valid PWM set.
        let mut s = Settings::default();
        s.set_many(&[
            ("output.protocol", Value::U32(1)),
            ("output.rate_hz", Value::U32(400)),
        ])
        .unwrap();
        let pwm = s.clone();
        assert_eq!(
            s.set("output.min_us", Value::U32(2_100)),
            Err(ParamError::Invalid(InvalidSettings::Output(
                OutputError::BadPulseLimits
            )))
        );
        assert_eq!(s, pwm);
    }

    #[test]
    fn a_multi_setting_change_is_checked_as_a_whole() {
        let mut s = Settings::default();
        // One by one, brushed → PWM at 400 Hz passes through an invalid set either way.
        assert!(s.set_text("output.protocol", "pwm").is_err());
        assert!(s.set_text("output.rate_hz", "400").is_err());
        s.set_text_pairs("output.protocol pwm output.rate_hz 400")
            .unwrap();
        assert_eq!(s.get(handles::OUTPUT_PROTOCOL), 1);
        assert_eq!(s.get(handles::OUTPUT_RATE_HZ), 400);
        // A bad pair anywhere refuses the whole line.
        let before = s.clone();
        assert_eq!(
            s.set_text_pairs("output.min_us 1100 output.max_us 1000"),
            Err(ParamError::Invalid(InvalidSettings::Output(
                OutputError::BadPulseLimits
            )))
        );
        assert_eq!(
            s.set_text_pairs("output.min_us 1100 output.max_us"),
            Err(ParamError::Unparsable)
        );
        assert_eq!(s, before);
    }
}
