//! The command line of `flight-sitl serve` (the runner's style: every option with a sentence
//! of help, values range-checked where they are parsed, flight settings through
//! `Settings::set_text`), turned into the server's [`Options`] by [`ServeCli::options`].

use std::net::SocketAddr;
use std::path::PathBuf;

use clap::Parser;
use telemetry::link::RateMode;

use super::{DEFAULT_ADDR, Options, SPEEDS, WorldOptions, default_dist};
use crate::runner::cli::{name_value, number_in};

/// Serves the web ground station against the firmware-in-the-loop world: each page that
/// connects gets its own world (both ends' applications on virtual Si4432s, the quad flown
/// by a scripted pilot, a minute per flight) in real time, and its phone is the module's
/// HM-10.
#[derive(Parser, Clone, Debug)]
#[command(
    name = "flight-sitl serve",
    version,
    after_help = "Examples:
  flight-sitl serve                               http://127.0.0.1:8018/
  flight-sitl serve 0.0.0.0:8018 --speed 2 --rate L50 --loss 0.05
  flight-sitl serve --set pid.roll.kp=0.004 --dist telemetry/ground-station/dist

Build the app first (telemetry/ground-station/README.md). Exit status 2 for a command-line
error or no built app, 1 if the address cannot be bound."
)]
pub struct ServeCli {
    /// Address to listen on (default 127.0.0.1:8018, this machine only).
    #[arg(value_name = "ADDR", default_value = DEFAULT_ADDR)]
    pub addr: SocketAddr,
    /// The built app (default: telemetry/ground-station/dist in this checkout).
    #[arg(long, value_name = "DIR")]
    pub dist: Option<PathBuf>,
    /// Virtual seconds per wall second (0.01..=100).
    #[arg(long, value_name = "X", default_value_t = 1.0, value_parser = speed)]
    pub speed: f64,
    /// Link rate mode: L50 (long range), M100, F250, F500 or F700 (fast, short range).
    #[arg(long, default_value_t = RateMode::F250)]
    pub rate: RateMode,
    /// Seed of the world's sensor noise and radio randomness.
    #[arg(long, value_name = "N", default_value_t = 7)]
    pub seed: u64,
    /// Extra random packet loss on the air, 0..=1 (both directions).
    #[arg(long, value_name = "P", default_value_t = 0.0, value_parser = loss)]
    pub loss: f64,
    /// A flight-controller setting NAME=VALUE, as the console's `set` takes it (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = name_value)]
    pub set: Vec<(String, String)>,
}

fn speed(s: &str) -> Result<f64, String> {
    number_in(s, *SPEEDS.start(), *SPEEDS.end(), "a speed-up factor")
}

fn loss(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 1.0, "the packet loss")
}

impl ServeCli {
    /// The server these options describe.
    ///
    /// # Errors
    /// A setting name or value refused by the flight settings, with the reason.
    pub fn options(&self) -> Result<Options, String> {
        let mut world = WorldOptions {
            rate: self.rate,
            seed: self.seed,
            packet_loss: self.loss,
            ..WorldOptions::default()
        };
        for (name, value) in &self.set {
            world
                .settings
                .set_text(name, value)
                .map_err(|e| format!("--set {name}={value}: {e}"))?;
        }
        Ok(Options {
            addr: self.addr,
            dist: self.dist.clone().unwrap_or_else(default_dist),
            speed: self.speed,
            world,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flight_app::settings::handles;
    use telemetry::link::RateMode;

    fn parse(s: &str) -> Result<ServeCli, clap::Error> {
        ServeCli::try_parse_from(std::iter::once("serve").chain(s.split_whitespace()))
    }

    #[test]
    fn parses_and_refuses() {
        let o = parse("").unwrap().options().unwrap();
        assert_eq!(o.addr.to_string(), DEFAULT_ADDR);
        assert_eq!((o.speed, o.world.rate), (1.0, RateMode::F250));
        let o =
            parse("0.0.0.0:9000 --speed 2 --rate l50 --seed 3 --loss 0.1 --set pid.roll.kp=0.004")
                .unwrap()
                .options()
                .unwrap();
        assert_eq!(o.addr.port(), 9000);
        assert_eq!(
            (o.speed, o.world.rate, o.world.seed),
            (2.0, RateMode::L50, 3)
        );
        assert_eq!(o.world.packet_loss, 0.1);
        assert_eq!(o.world.settings.get(handles::PID_ROLL_KP), 0.004);
        for bad in [
            "nowhere",
            "--speed 0",
            "--speed 1000",
            "--loss 2",
            "--rate F1000",
            "--sped 2",
        ] {
            assert!(parse(bad).is_err(), "{bad} accepted");
        }
        assert!(parse("--set no.such=1").unwrap().options().is_err());
    }
}
