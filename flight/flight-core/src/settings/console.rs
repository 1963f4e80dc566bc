//! The USB console's command language: one command per line, words separated by spaces.
//!
//! ```text
//! help                      list the commands
//! list [PREFIX]             every setting (or those starting with PREFIX) with its value
//! get NAME                  one setting
//! set NAME VALUE [NAME VALUE]…  change settings together (in RAM; refused while armed);
//!                           refused whole if any value, or the set they make, cannot run
//! save                      write changed settings to flash (refused while armed)
//! defaults                  factory values (in RAM until saved)
//! status                    arm state, link, battery, mode
//! bind                      open the bind window (refused while armed)
//! phrase TEXT…              set the binding phrase (the rest of the line, spaces inside
//!                           count; refused while armed; saved at once, never shown again)
//! phrase clear              remove it: the link runs unauthenticated
//! phrase                    show the key's fingerprint (to compare with the module)
//! magcal start|status|save|cancel   magnetometer calibration (disarmed): collect while the
//!                           frame is turned, show the fit and its checks, store it if
//!                           they pass, or drop it
//! ```

use core::fmt::Write;

use super::decimal::Shortest;
use super::params::Settings;
use telemetry::settings::{Kind, Value, find};

/// A parsed line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command<'a> {
    /// Show the commands.
    Help,
    /// List settings whose name starts with the prefix ("" = all).
    List(&'a str),
    /// Show one setting.
    Get(&'a str),
    /// Change one setting.
    Set {
        /// Setting name.
        name: &'a str,
        /// Value text.
        value: &'a str,
    },
    /// Change several settings together: the `NAME VALUE …` pairs, for
    /// [`Settings::set_text_pairs`].
    SetAll(&'a str),
    /// Persist.
    Save,
    /// Factory values.
    Defaults,
    /// Live status.
    Status,
    /// Open the bind window (the deliberate act that binds this controller to a module),
    /// with the binding phrase for it: the rest of the line, trimmed (not yet checked: see
    /// `telemetry::link::check_phrase`); empty: bind without a phrase.
    Bind(&'a str),
    /// Magnetometer calibration.
    Magcal(MagcalAction),
    /// An empty line.
    Nothing,
}

/// What `magcal` is asked to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MagcalAction {
    /// Start collecting magnetometer readings (drops any earlier ones).
    Start,
    /// Show the readings collected and the fit's checks.
    Status,
    /// Fit, check and, if the checks pass, store in the settings (and save).
    Save,
    /// Stop and drop the readings.
    Cancel,
}

/// Why a line was not understood.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConsoleError {
    /// Unknown command word.
    UnknownCommand,
    /// Missing or extra words.
    WrongArguments,
}

impl core::fmt::Display for ConsoleError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ConsoleError::UnknownCommand => "unknown command (try help)",
            ConsoleError::WrongArguments => "wrong arguments (try help)",
        })
    }
}

impl core::error::Error for ConsoleError {}

/// Parses one line (without its line ending).
pub fn parse_line(line: &str) -> Result<Command<'_>, ConsoleError> {
    let mut words = line.split_ascii_whitespace();
    let Some(word) = words.next() else {
        return Ok(Command::Nothing);
    };
    if word == "set" {
        let pairs = line.trim_start().get(3..).unwrap_or("").trim();
        let count = pairs.split_ascii_whitespace().count();
        if count > 2 && count % 2 == 0 && count <= 2 * super::params::MAX_PAIRS {
            return Ok(Command::SetAll(pairs));
        }
    }
    if word == "bind" {
        // The phrase is the rest of the line, spaces inside included.
        return Ok(Command::Bind(
            line.trim_start().get(4..).unwrap_or("").trim(),
        ));
    }
    let a = words.next();
    let b = words.next();
    if words.next().is_some() {
        return Err(ConsoleError::WrongArguments);
    }
    match (word, a, b) {
        ("help", None, None) => Ok(Command::Help),
        ("list", prefix, None) => Ok(Command::List(prefix.unwrap_or(""))),
        ("get", Some(name), None) => Ok(Command::Get(name)),
        ("set", Some(name), Some(value)) => Ok(Command::Set { name, value }),
        ("save", None, None) => Ok(Command::Save),
        ("defaults", None, None) => Ok(Command::Defaults),
        ("status", None, None) => Ok(Command::Status),
        ("magcal", Some(action), None) => match action {
            "start" => Ok(Command::Magcal(MagcalAction::Start)),
            "status" => Ok(Command::Magcal(MagcalAction::Status)),
            "save" => Ok(Command::Magcal(MagcalAction::Save)),
            "cancel" => Ok(Command::Magcal(MagcalAction::Cancel)),
            _ => Err(ConsoleError::WrongArguments),
        },
        (
            "help" | "list" | "get" | "set" | "save" | "defaults" | "status" | "bind" | "magcal",
            _,
            _,
        ) => Err(ConsoleError::WrongArguments),
        _ => Err(ConsoleError::UnknownCommand),
    }
}

/// Text as `{}` writes it, without the width and precision no console line uses: `&str`'s
/// and `bool`'s own `Display` go through `Formatter::pad`, which counts characters (248 B
/// of the Sparky2's flash, measured, for nothing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Word<'a>(pub &'a str);

impl<'a> Word<'a> {
    /// `true` or `false`, as `{}` writes a `bool`.
    pub fn of_bool(b: bool) -> Word<'a> {
        Word(if b { "true" } else { "false" })
    }
}

impl core::fmt::Display for Word<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.0)
    }
}

/// A signed whole number as `{}` writes it, through `u32`'s formatter (the console's one
/// integer formatter: `i32`'s own cost the Sparky2 176 B more flash, measured).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Signed(pub i32);

impl core::fmt::Display for Signed {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.0 < 0 {
            f.write_str("-")?;
        }
        write!(f, "{}", self.0.unsigned_abs())
    }
}

/// Writes `name = value` the way `set` accepts it back.
pub fn write_setting(out: &mut dyn Write, settings: &Settings, name: &str) -> core::fmt::Result {
    let Some((_, param)) = find(name) else {
        return writeln!(out, "{}: no such setting", Word(name));
    };
    let value = settings.by_name(name);
    if value.is_some() {
        write!(out, "{} = ", Word(name))?;
    }
    match (param.kind, value) {
        (Kind::Choice(names), Some(Value::U32(i))) => {
            writeln!(
                out,
                "{}",
                Word(names.get(i as usize).copied().unwrap_or("?"))
            )
        }
        (_, Some(Value::F32(v))) => writeln!(out, "{}", Shortest(v)),
        (_, Some(Value::U32(v))) => writeln!(out, "{v}"),
        (_, None) => writeln!(out, "{}: no such setting", Word(name)),
    }
}

/// Writes every setting starting with `prefix`.
pub fn write_list(out: &mut dyn Write, settings: &Settings, prefix: &str) -> core::fmt::Result {
    for (p, _) in settings.iter().filter(|(p, _)| p.name.starts_with(prefix)) {
        write_setting(out, settings, p.name)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::handles;

    #[test]
    fn words_and_signed_numbers_read_as_core_writes_them() {
        for v in [i32::MIN, -1_250, -1, 0, 7, 473_977_419, i32::MAX] {
            assert_eq!(format!("{}", Signed(v)), format!("{v}"));
        }
        assert_eq!(format!("[{}]", Word("up")), "[up]");
        assert_eq!(format!("{}", Word::of_bool(false)), "false");
    }

    #[test]
    fn parses_commands_and_refuses_garbage() {
        assert_eq!(
            parse_line("  set  pid.roll.kp 0.004 "),
            Ok(Command::Set {
                name: "pid.roll.kp",
                value: "0.004"
            })
        );
        assert_eq!(parse_line("list pid."), Ok(Command::List("pid.")));
        assert_eq!(parse_line("list"), Ok(Command::List("")));
        assert_eq!(parse_line(""), Ok(Command::Nothing));
        assert_eq!(parse_line("get"), Err(ConsoleError::WrongArguments));
        assert_eq!(parse_line("set a b c"), Err(ConsoleError::WrongArguments));
        assert_eq!(
            parse_line(" set output.protocol pwm  output.rate_hz 400 "),
            Ok(Command::SetAll("output.protocol pwm  output.rate_hz 400"))
        );
        assert_eq!(
            parse_line(&format!("set{}", " a 1".repeat(9))),
            Err(ConsoleError::WrongArguments),
            "at most eight pairs"
        );
        assert_eq!(parse_line("rm -rf"), Err(ConsoleError::UnknownCommand));
        assert_eq!(
            parse_line("  bind  amber kettle  under the oak "),
            Ok(Command::Bind("amber kettle  under the oak"))
        );
        assert_eq!(parse_line("bind"), Ok(Command::Bind("")));
        assert_eq!(parse_line("binds x"), Err(ConsoleError::UnknownCommand));
        assert_eq!(parse_line("phrase x"), Err(ConsoleError::UnknownCommand));
    }

    #[test]
    fn output_round_trips_through_set() {
        let mut s = Settings::default();
        s.set_text("output.protocol", "oneshot125").unwrap();
        let mut text = heapless::String::<512>::new();
        write_list(&mut text, &s, "output.").unwrap();
        assert!(
            text.starts_with("output.protocol = oneshot125\noutput.rate_hz = 32000\n"),
            "{text}"
        );
        // Every printed line is accepted back by `set`.
        let mut again = Settings::default();
        for line in text.lines() {
            let (name, value) = line.split_once(" = ").unwrap();
            again.set_text(name, value).unwrap();
        }
        assert_eq!(
            again.get(handles::OUTPUT_PROTOCOL),
            s.get(handles::OUTPUT_PROTOCOL)
        );
    }

    #[test]
    fn every_settable_value_reads_back_from_its_text() {
        use crate::settings::decimal::Shortest;
        use crate::settings::{PARAMS, ParamText, Value};
        for p in PARAMS {
            let Kind::F32 { min, max } = p.kind else {
                continue;
            };
            // Both ends, their neighbours, and a sweep of bit patterns in between (positive
            // and negative halves apart: the bits are ordered by magnitude).
            let mut values = vec![min, max, min.next_up(), max.next_down()];
            for (from, to) in [(min.max(0.0), max), (max.min(-0.0), min)] {
                if from.abs() > to.abs() || from.is_sign_negative() != to.is_sign_negative() {
                    continue;
                }
                let (a, b) = (from.to_bits(), to.to_bits());
                let step = ((b - a) / 20_000).max(1);
                values.extend((a..=b).step_by(step as usize).map(f32::from_bits));
            }
            for v in values.into_iter().filter(|v| (min..=max).contains(v)) {
                let text = format!("{}", Shortest(v));
                assert_eq!(text, format!("{v}"), "{}", p.name);
                assert_eq!(p.parse(&text), Ok(Value::F32(v)), "{} = {text}", p.name);
            }
        }
    }
}
