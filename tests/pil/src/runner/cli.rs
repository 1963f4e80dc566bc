//! The `pil` command line: `cargo run --release -p pil -- SCENARIO [options]`. Out-of-range
//! values and misspelt flags are refused with the reason (exit status 2), as every tool of
//! the workspace does; flight-sitl's number parser and rate names are reused.

use std::path::PathBuf;

use clap::{Parser, ValueEnum};
use telemetry::link::RateMode;

use super::{Kind, Options, image};
use crate::board::flight::FlightBoardKind;

/// The images of `cargo xtask dist`, unchanged, on emulated STM32F405 and nRF52840 boards
/// against the simulated radios, sensors, handset and quadrotor, flying a named scenario;
/// prints flight-sitl's figures plus each image's (or JSON).
#[derive(Parser, Clone, Debug)]
#[command(
    name = "pil",
    version,
    after_help = "Scenarios:
  boot            both boards power up: every task polled, the link up, no reset (1 s)
  hover           take off, climb to --altitude (5 m) and hold; 30 s unless --duration
  link-cut        climb to --altitude (30 m), the air path is cut: failsafe, descent, landing
  imu-stall       hovering, the MPU-9250's data-ready stops for 1 s
  i2c-stuck       the MS5611 holds SDA low from power-on; the image must recover the bus
  settings-save   the phone changes a setting, the flight side saves it, power cycle
  panic           a DMA transfer error on the IMU's stream panics the image in the air

Examples:
  pil boot --json
  pil hover --rate F250 --seed 7
  pil link-cut --altitude 30 --json
  pil hover --board sparky2 --lsi-hz 47000
  pil hover --board sparky2 --gps --console-busy
  pil hover --flight-image my-flight.elf      (your own modified image)

Exit status: 0 when the run was made and its criteria met, 1 when a criterion failed or
the run could not be made, 2 for a command-line error."
)]
pub struct Cli {
    /// The scenario (list below).
    #[arg(value_enum)]
    pub scenario: KindArg,
    /// The flight controller board.
    #[arg(long, value_enum, default_value_t = BoardArg::Brushedsparky)]
    pub board: BoardArg,
    /// Link rate mode: L50, M100, F250, F500 or F700.
    #[arg(long, default_value_t = RateMode::F250)]
    pub rate: RateMode,
    /// Seed of the world's noise and radio randomness; same seed, same run.
    #[arg(long, value_name = "N", default_value_t = 7)]
    pub seed: u64,
    /// The flight board's LSI (the IWDG's clock), Hz, within the STM32F405's 17 000–47 000
    /// (DS8626); the model's nominal 32 000 unless given.
    #[arg(long, value_name = "F", value_parser = lsi)]
    pub lsi_hz: Option<f64>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    /// The flight image (default: `dist/flight-BOARD.elf`).
    #[arg(long, value_name = "PATH")]
    pub flight_image: Option<PathBuf>,
    /// The module image (default: dist/module-nrf52840.elf).
    #[arg(long, value_name = "PATH")]
    pub module_image: Option<PathBuf>,
    /// Virtual duration after the 4 s warm-up, s (0 < S ≤ 3600; default: the scenario's).
    #[arg(long, value_name = "S", value_parser = duration)]
    pub duration: Option<f64>,
    /// Altitude the pilot climbs to, m (1 ≤ M ≤ 120).
    #[arg(long, value_name = "M", value_parser = altitude)]
    pub altitude: Option<f64>,
    /// Time of the scenario's fault, s (2.5 ≤ S ≤ 3600).
    #[arg(long, value_name = "S", value_parser = at)]
    pub at: Option<f64>,
    /// The binding phrase on both ends (default: "amber kettle under the oak").
    #[arg(long, value_name = "TEXT", conflicts_with = "no_phrase")]
    pub phrase: Option<String>,
    /// No binding phrase (an unauthenticated link).
    #[arg(long)]
    pub no_phrase: bool,
    /// A u-blox on the Sparky2's GPS port (USART1, 115 200 Bd once configured).
    #[arg(long)]
    pub gps: bool,
    /// From the take-off a USB host at the flight console types `status` every 10 ms
    /// (the loop's jitter with the console busy; plugged once armed: a host at the console
    /// refuses arming).
    #[arg(long)]
    pub console_busy: bool,
    /// The lockstep quantum, µs (1 ≤ U ≤ 100).
    #[arg(long, value_name = "U", value_parser = quantum, default_value_t = 5.0)]
    pub quantum_us: f64,
}

/// A scenario on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum KindArg {
    /// `boot`.
    Boot,
    /// `hover`.
    Hover,
    /// `link-cut`.
    LinkCut,
    /// `imu-stall`.
    ImuStall,
    /// `i2c-stuck`.
    I2cStuck,
    /// `settings-save`.
    SettingsSave,
    /// `panic`.
    Panic,
}

impl KindArg {
    fn kind(self) -> Kind {
        match self {
            KindArg::Boot => Kind::Boot,
            KindArg::Hover => Kind::Hover,
            KindArg::LinkCut => Kind::LinkCut,
            KindArg::ImuStall => Kind::ImuStall,
            KindArg::I2cStuck => Kind::I2cStuck,
            KindArg::SettingsSave => Kind::SettingsSave,
            KindArg::Panic => Kind::Panic,
        }
    }
}

/// A board on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BoardArg {
    /// BrushedSparky.
    Brushedsparky,
    /// Sparky2.
    Sparky2,
}

fn number(s: &str, lo: f64, hi: f64, what: &str) -> Result<f64, String> {
    flight_sitl::runner::cli::number_in(s, lo, hi, what)
}

fn lsi(s: &str) -> Result<f64, String> {
    number(
        s,
        17_000.0,
        47_000.0,
        "the LSI frequency (Hz, DS8626: 17 000–47 000)",
    )
}

fn duration(s: &str) -> Result<f64, String> {
    let v = number(s, 0.0, 3_600.0, "the duration (s)")?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("the duration (s) must be greater than 0, got {s}"))
    }
}

fn altitude(s: &str) -> Result<f64, String> {
    number(s, 1.0, 120.0, "the altitude (m)")
}

fn at(s: &str) -> Result<f64, String> {
    number(
        s,
        flight_sitl::runner::pilot::TAKEOFF_S,
        3_600.0,
        "the fault time (s)",
    )
}

fn quantum(s: &str) -> Result<f64, String> {
    number(s, 1.0, 100.0, "the quantum (µs)")
}

impl Cli {
    /// What the parser cannot see: a combination the boards do not have.
    ///
    /// # Errors
    /// The reason, for the command line's error message.
    pub fn check(&self) -> Result<(), String> {
        if self.gps && self.board != BoardArg::Sparky2 {
            return Err("--gps: the BrushedSparky has no GPS port (use --board sparky2)".into());
        }
        Ok(())
    }

    /// The run these options describe.
    pub fn options(&self) -> Options {
        let kind = self.scenario.kind();
        let mut o = Options::new(kind);
        o.board = match self.board {
            BoardArg::Brushedsparky => FlightBoardKind::BrushedSparky,
            BoardArg::Sparky2 => FlightBoardKind::Sparky2,
        };
        o.sitl.rate = self.rate;
        o.sitl.seed = self.seed;
        o.sitl.duration_s = self.duration;
        o.sitl.altitude_m = self.altitude;
        o.sitl.at_s = self.at;
        o.lsi_hz = self.lsi_hz;
        o.sitl.gps = self.gps;
        o.console_busy = self.console_busy;
        o.flight_image = self
            .flight_image
            .clone()
            .unwrap_or_else(|| image::dist_dir().join(format!("flight-{}.elf", o.board.name())));
        if let Some(m) = &self.module_image {
            o.module_image = m.clone();
        }
        o.phrase = if self.no_phrase {
            None
        } else {
            Some(
                self.phrase
                    .clone()
                    .unwrap_or_else(|| super::DEFAULT_PHRASE.to_owned()),
            )
        };
        o.quantum_ns = (self.quantum_us * 1e3).round() as u64;
        o
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("pil").chain(s.split_whitespace()))
    }

    #[test]
    fn every_scenario_by_name_and_a_full_command_line() {
        for k in Kind::ALL {
            assert_eq!(parse(k.name()).unwrap().options().kind, k);
        }
        let o = parse(
            "link-cut --board sparky2 --rate L50 --seed 3 --lsi-hz 47000 --altitude 20 \
             --flight-image my.elf --quantum-us 10 --no-phrase --json",
        )
        .unwrap()
        .options();
        assert_eq!(o.board, FlightBoardKind::Sparky2);
        assert_eq!(o.sitl.rate, RateMode::L50);
        assert_eq!(o.sitl.seed, 3);
        assert_eq!(o.lsi_hz, Some(47_000.0));
        assert_eq!(o.sitl.altitude_m, Some(20.0));
        assert_eq!(o.flight_image, PathBuf::from("my.elf"));
        assert_eq!(o.quantum_ns, 10_000);
        assert_eq!(o.phrase, None);
        let d = parse("hover --board sparky2").unwrap().options();
        assert!(d.flight_image.ends_with("flight-sparky2.elf"));
        assert!(d.module_image.ends_with("module-nrf52840.elf"));
        assert_eq!(d.phrase.as_deref(), Some(super::super::DEFAULT_PHRASE));
    }

    #[test]
    fn nonsense_is_refused() {
        for bad in [
            "hovr",
            "hover --board sparky3",
            "hover --lsi-hz 16000",
            "hover --lsi-hz 48000",
            "hover --rate F1000",
            "hover --duration 0",
            "hover --altitude 500",
            "hover --quantum-us 0",
            "hover --phrase x --no-phrase",
            "hover --seed -1",
        ] {
            assert!(parse(bad).is_err(), "{bad} accepted");
        }
        assert!(parse("hover --gps").unwrap().check().is_err());
        let busy = parse("hover --board sparky2 --gps --console-busy").unwrap();
        assert!(busy.check().is_ok());
        let o = busy.options();
        assert!(o.sitl.gps && o.console_busy);
    }
}
