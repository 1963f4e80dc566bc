//! `taulink-sim --serve [ADDR]`: the web ground station against the firmware-in-the-loop
//! world of `flight-sitl` (`flight_sitl::serve`: both ends' own applications on virtual
//! Si4432s, the quad flown by a scripted pilot, the page as the phone on the module's
//! HM-10) — the same server as `flight-sitl serve`. The link options that world takes
//! (`--rate`, `--seed`, `--loss`) come from this command line; the served world places the
//! two ends 100 m apart on 433 MHz, so the other link options do not apply to it.

use flight_sitl::serve::{Options, WorldOptions, default_dist};

use crate::Cli;

/// The server's options from the command line (`--serve [ADDR] [--dist DIR] [--speed X]`
/// with `--rate`, `--seed`, `--loss`); `None` without `--serve`.
pub fn options(cli: &Cli) -> Option<Options> {
    Some(Options {
        addr: cli.serve?,
        dist: cli.dist.clone().unwrap_or_else(default_dist),
        speed: cli.speed,
        world: WorldOptions {
            rate: cli.rate,
            seed: cli.seed,
            packet_loss: cli.loss,
            ..WorldOptions::default()
        },
    })
}

/// Runs the server until the process ends; returns the exit code on a startup error.
pub fn main(options: Options) -> i32 {
    flight_sitl::serve::main(options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;
    use telemetry::link::RateMode;

    #[test]
    fn the_link_options_reach_the_served_world() {
        let cli = Cli::try_parse_from(
            "taulink-sim --serve 127.0.0.1:9001 --rate L50 --seed 9 --loss 0.2 --speed 3"
                .split_whitespace(),
        )
        .unwrap();
        let o = options(&cli).unwrap();
        assert_eq!(o.addr.port(), 9001);
        assert_eq!(o.speed, 3.0);
        assert_eq!(
            (o.world.rate, o.world.seed, o.world.packet_loss),
            (RateMode::L50, 9, 0.2)
        );
        let plain = Cli::try_parse_from(["taulink-sim"]).unwrap();
        assert!(options(&plain).is_none());
    }
}
