//! The command line of `flight-sitl` (clap derive, the shared style of the host tools):
//! every option with a sentence of help, values range-checked where they are parsed, flight
//! settings through `Settings::set_text` and module settings through
//! `module_core::settings::Settings::set_text`, so nonsense is refused with a clear message
//! and a non-zero exit before anything flies. [`Cli::options`] turns it into [`Options`].

use std::sync::LazyLock;

use clap::builder::PossibleValue;
use clap::{Parser, ValueEnum};
use telemetry::link::RateMode;

use super::{Kind, Options};

/// The flight firmware's own application (`flight_app::app::FlightApp`) flying a simulated
/// 250-class quad over the TauLink air link from a simulated module, in virtual time, through
/// a named scenario; prints its figures (or JSON) and can draw them.
#[derive(Parser, Clone, Debug)]
#[command(
    name = "flight-sitl",
    version,
    allow_negative_numbers = true,
    after_help = "Scenarios:
  hover               take off, climb to --altitude (5 m) and hold
  link-cut            climb to --altitude (30 m), cut the air path for good (or at --at)
  power-cycle         armed on the ground, flight controller off 1 s at --at (4 s); re-arm, fly
  handset-unplugged   hovering at 10 m, the handset input stops at the module at --at
  imu-stall           hovering, IMU data-ready stops for 1 s at --at
  imu-frozen          hovering, IMU repeats its last sample for 1 s at --at
  radio-stuck-irq     hovering, the flight RFM22B's nIRQ reads low for 2 s at --at
  radio-brownout      hovering, the flight RFM22B browns out for 2 s at --at
  settings-corrupt    the flight settings flash is corrupted at boot; the pilot tries to fly
  low-battery         hovering, the pack falls 50 mV/s from 4.0 V from --at
  altitude-hold       hovering at --altitude (10 m), the mode switch goes to altitude hold,
                      throttle centred, for a minute (indoor INS on the baro; --gps: full INS)
  position-hold       as altitude-hold in position hold, with a GPS receiver (--wind M/S)
  loiter              position hold in loiter; the pilot pushes pitch forward (half stick)
                      for 3 s and releases: how far it moved, how well the new spot is held
  table               the acceptance runs of issues 12/13/16, as a Markdown table
                      (--check: fail if the README's table differs; --write: rewrite it)

  oneshot-experiment  the seed's OneShot125 experiment (its own options: --runs N, --json,
                      --plot DIR; see `flight-sitl oneshot-experiment --help`)
  serve [ADDR]        the web ground station against this world, a scripted pilot flying
                      (its own options: --speed X, --dist DIR, --rate, --seed, --loss, --set;
                      see `flight-sitl serve --help`)

Examples:
  flight-sitl hover --rate F500 --json
  flight-sitl link-cut --altitude 60 --rate L50 --plot out
  flight-sitl link-cut --set failsafe.descent_mps=1.5 --seed 3
  flight-sitl link-cut --gps              (the failsafe holds position 30 s, then descends)
  flight-sitl position-hold --wind 3 --json
  flight-sitl handset-unplugged --module-set input_timeout_ms=1000
  flight-sitl hover --duration 60 --log hover.ulg   (every sample; `replay hover.ulg`)
  flight-sitl table > acceptance.md
  flight-sitl table --check               (CI: the README's runner table is current)

Exit status: 0 when the run was made, 2 for a command-line error (a misspelt flag, a value
out of range, a setting refused), 1 if the scenario could not be flown as asked."
)]
pub struct Cli {
    /// The scenario to fly (list below), or `table` for the acceptance table.
    #[arg(value_enum)]
    pub scenario: ScenarioArg,
    /// Link rate mode: L50 (long range), M100, F250, F500 or F700 (fast, short range).
    #[arg(long, default_value_t = RateMode::F250)]
    pub rate: RateMode,
    /// Seed of the world's sensor noise and radio randomness; same seed, same run.
    #[arg(long, value_name = "N", default_value_t = 7)]
    pub seed: u64,
    /// A flight-controller setting NAME=VALUE, as the console's `set` takes it (repeatable;
    /// applied in order, each checked with the whole set).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = name_value)]
    pub set: Vec<(String, String)>,
    /// A module setting NAME=VALUE (role, input, output, band, tx_power, failsafe, bind_id,
    /// input_timeout_ms, telemetry_ratio; repeatable). Its air rate follows --rate.
    #[arg(long = "module-set", value_name = "NAME=VALUE", value_parser = name_value)]
    pub module_set: Vec<(String, String)>,
    /// Time of the scenario's fault, seconds of virtual time (2.5 ≤ S ≤ 3600; default: 3 s
    /// after the pilot starts holding the altitude; link-cut: when the climb reaches it;
    /// power-cycle: 4 s).
    #[arg(long, value_name = "S", value_parser = at)]
    pub at: Option<f64>,
    /// Altitude the pilot climbs to before the fault, metres (1 ≤ M ≤ 120).
    #[arg(long, value_name = "M", value_parser = altitude)]
    pub altitude: Option<f64>,
    /// Virtual duration, seconds (0 < S ≤ 3600; default: long enough to play the scenario out).
    #[arg(long, value_name = "S", value_parser = duration)]
    pub duration: Option<f64>,
    /// A simulated GPS receiver on the flight controller (5 Hz, 100 ms latency, 0.5 m
    /// noise) and the full INS (`ins.mode ins`); position-hold and loiter always have one.
    #[arg(long)]
    pub gps: bool,
    /// A steady wind from the north, m/s (0 ≤ M/S ≤ 15).
    #[arg(long, value_name = "M/S", value_parser = wind, default_value_t = 0.0)]
    pub wind: f64,
    /// Write the flight controller's log (ULog, what pyulog and PlotJuggler read) to FILE;
    /// the profile is `full` (every sample: replayable) unless --set log.profile says
    /// otherwise. A run with reboots writes each later boot's log next to it
    /// (FILE.boot2.ulg, …).
    #[arg(long, value_name = "FILE.ulg")]
    pub log: Option<std::path::PathBuf>,
    /// Print the figures as one JSON object on stdout (fields in the README).
    #[arg(long)]
    pub json: bool,
    /// `--plot DIR`: draw altitude, attitude, motors and link state over time into DIR.
    #[command(flatten)]
    pub plot: sim_plot::PlotArgs,
    /// No progress bar (the `table` mode).
    #[arg(long, short)]
    pub quiet: bool,
    /// With `table`: fail (exit 1) when the README's runner table differs from this run.
    #[arg(long, conflicts_with = "write")]
    pub check: bool,
    /// With `table`: rewrite the README's runner table with this run.
    #[arg(long)]
    pub write: bool,
}

/// A scenario name on the command line: a [`Kind`] by its [`Kind::name`], or `table`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScenarioArg {
    /// Fly one scenario.
    Run(Kind),
    /// The acceptance table.
    Table,
}

/// Every scenario name in `--help` order: the README's, then `table`.
static SCENARIO_ARGS: LazyLock<Vec<ScenarioArg>> = LazyLock::new(|| {
    Kind::ALL
        .into_iter()
        .map(ScenarioArg::Run)
        .chain([ScenarioArg::Table])
        .collect()
});

impl ValueEnum for ScenarioArg {
    fn value_variants<'a>() -> &'a [Self] {
        &SCENARIO_ARGS
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(match self {
            Self::Run(kind) => kind.name(),
            Self::Table => "table",
        }))
    }
}

impl ScenarioArg {
    /// The scenario (None for `table`).
    pub fn kind(self) -> Option<Kind> {
        match self {
            Self::Run(kind) => Some(kind),
            Self::Table => None,
        }
    }
}

/// A finite number within `lo..=hi` (`what` names it in the error): the number parse of
/// flight-sitl's and taulink-sim's command lines.
pub fn number_in(s: &str, lo: f64, hi: f64, what: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number"))?;
    if !v.is_finite() || v < lo || v > hi {
        return Err(format!("{what} must be within {lo}..={hi}, got {s}"));
    }
    Ok(v)
}

fn at(s: &str) -> Result<f64, String> {
    number_in(s, super::pilot::TAKEOFF_S, 3_600.0, "the fault time (s)")
}

fn altitude(s: &str) -> Result<f64, String> {
    number_in(s, 1.0, 120.0, "the altitude (m)")
}

fn wind(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 15.0, "the wind (m/s)")
}

fn duration(s: &str) -> Result<f64, String> {
    let v = number_in(s, 0.0, 3_600.0, "the duration (s)")?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("the duration (s) must be greater than 0, got {s}"))
    }
}

pub(crate) fn name_value(s: &str) -> Result<(String, String), String> {
    let (n, v) = s
        .split_once('=')
        .ok_or_else(|| format!("{s:?}: expected NAME=VALUE, e.g. failsafe.descent_mps=1.0"))?;
    if n.trim().is_empty() || v.trim().is_empty() {
        return Err(format!("{s:?}: expected NAME=VALUE with both parts"));
    }
    Ok((n.trim().to_owned(), v.trim().to_owned()))
}

impl Cli {
    /// The run these options describe, with every setting applied.
    ///
    /// # Errors
    /// A setting name or value refused by the flight or module settings, with the reason.
    pub fn options(&self) -> Result<Options, String> {
        // The scenario's own needs (INS mode, hold mode, receiver) first; --set may change them.
        let mut o = match self.scenario.kind() {
            Some(kind) => Options::for_kind(kind, self.gps)?,
            None => Options::factory(),
        };
        o.wind_mps = self.wind;
        o.rate = self.rate;
        o.seed = self.seed;
        o.at_s = self.at;
        o.altitude_m = self.altitude;
        o.duration_s = self.duration;
        if self.log.is_some() {
            o.settings
                .put(
                    flight_app::settings::handles::LOG_PROFILE,
                    flight_app::logging::Profile::Full.index(),
                )
                .map_err(|e| format!("--log: {e}"))?;
        }
        for (name, value) in &self.set {
            o.settings
                .set_text(name, value)
                .map_err(|e| format!("--set {name}={value}: {e}"))?;
        }
        if !self.module_set.is_empty() {
            // From the world's pairing: factory, bound, at --rate.
            let mut m = super::bound_module_settings(o.rate);
            for (name, value) in &self.module_set {
                if name == "rate" {
                    return Err("--module-set rate: the link's rate mode is --rate".into());
                }
                m.set_text(name, value).map_err(|e| {
                    format!(
                        "--module-set {name}={value}: {e} (names: {})",
                        module_core::settings::text::names()
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                })?;
            }
            o.module_settings = Some(m);
        }
        if (self.check || self.write) && self.scenario != ScenarioArg::Table {
            return Err("--check and --write are for `table` (the README's runner table)".into());
        }
        if let Some(kind) = self.scenario.kind()
            && self.at.is_some()
            && !kind.has_fault_time()
        {
            return Err(format!("--at: {} has no fault to time", kind.name()));
        }
        Ok(o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flight_app::settings::handles;

    fn parse(s: &str) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("flight-sitl").chain(s.split_whitespace()))
    }

    #[test]
    fn every_scenario_is_named_by_its_kind_and_table_by_table() {
        for kind in Kind::ALL {
            assert_eq!(parse(kind.name()).unwrap().scenario.kind(), Some(kind));
        }
        assert_eq!(parse("table").unwrap().scenario, ScenarioArg::Table);
    }

    #[test]
    fn check_and_write_are_for_the_table_only() {
        assert!(parse("table --check").unwrap().options().is_ok());
        assert!(parse("table --write").unwrap().options().is_ok());
        assert!(parse("table --check --write").is_err());
        assert!(parse("hover --check").unwrap().options().is_err());
    }

    #[test]
    fn parses_a_full_command_line() {
        let cli = parse(
            "link-cut --rate l50 --seed 3 --altitude 60 --set failsafe.descent_mps=1.5 \
             --module-set input_timeout_ms=750 --json --duration 90",
        )
        .unwrap();
        assert_eq!(cli.scenario, ScenarioArg::Run(Kind::LinkCut));
        let o = cli.options().unwrap();
        assert_eq!(o.rate, RateMode::L50);
        assert_eq!(o.seed, 3);
        assert_eq!(o.altitude_m, Some(60.0));
        assert_eq!(o.duration_s, Some(90.0));
        assert_eq!(o.settings.get(handles::FAILSAFE_DESCENT_MPS), 1.5);
        let m = o.module_settings.unwrap();
        assert_eq!(m.input_timeout_ms, 750);
        assert_eq!(m.rate, RateMode::L50);
        assert_eq!(m.bind_id, super::super::RUNNER_BIND_ID);
        // Without --module-set the world pairs the ends itself.
        assert_eq!(
            parse("hover").unwrap().options().unwrap().module_settings,
            None
        );
        assert!(cli.json);
    }

    /// The index of choice `text` of setting `name`.
    fn choice(name: &str, text: &str) -> u32 {
        let mut s = flight_app::settings::Settings::default();
        s.set_text(name, text).unwrap();
        match s.by_name(name) {
            Some(flight_app::settings::Value::U32(i)) => i,
            other => panic!("{name} is no choice: {other:?}"),
        }
    }

    #[test]
    fn hold_scenarios_bring_their_settings_and_receiver() {
        let o = parse("position-hold --wind 3").unwrap().options().unwrap();
        assert!(o.gps);
        assert_eq!(o.wind_mps, 3.0);
        assert_eq!(o.settings.get(handles::INS_MODE), choice("ins.mode", "ins"));
        assert_eq!(
            o.settings.get(handles::MODE_SWITCH_HIGH),
            choice("mode.switch_high", "position-hold")
        );
        let a = parse("altitude-hold").unwrap().options().unwrap();
        assert!(!a.gps);
        assert_eq!(
            a.settings.get(handles::INS_MODE),
            choice("ins.mode", "ins_indoor")
        );
        let c = parse("link-cut --gps").unwrap().options().unwrap();
        assert!(c.gps);
        assert_eq!(c.settings.get(handles::INS_MODE), choice("ins.mode", "ins"));
        // Plain link-cut: factory settings, no receiver.
        let plain = parse("link-cut").unwrap().options().unwrap();
        assert!(!plain.gps);
        assert_eq!(plain.settings, Options::factory().settings);
        // --set comes after the scenario's needs.
        let l = parse("loiter --set ins.mode=ins_indoor")
            .unwrap()
            .options()
            .unwrap();
        assert_eq!(
            l.settings.get(handles::INS_MODE),
            choice("ins.mode", "ins_indoor")
        );
    }

    #[test]
    fn nonsense_is_refused() {
        for bad in [
            "hover --rat F250",
            "hover --rate F1000",
            "hovr",
            "link-cut --altitude 0",
            "link-cut --altitude 500",
            "link-cut --at 1",
            "link-cut --at nan",
            "hover --duration -5",
            "hover --duration 0",
            "hover --set failsafe.descent_mps",
            "hover --seed -1",
            "position-hold --wind 20",
            "position-hold --wind -1",
        ] {
            assert!(parse(bad).is_err(), "{bad} accepted");
        }
        for refused in [
            "hover --set no.such=1",
            "hover --set failsafe.descent_mps=9",
            "hover --set output.protocol=pwm",
            "hover --module-set colour=red",
            "hover --module-set tx_power=9",
            "hover --module-set rate=M100",
            "hover --at 10",
            "loiter --at 10",
        ] {
            let err = parse(refused).unwrap().options().unwrap_err();
            assert!(!err.is_empty(), "{refused}");
        }
    }
}
