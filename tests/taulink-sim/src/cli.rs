//! The command line of `taulink-sim` (clap derive): every option with a sentence of help,
//! values checked where they are parsed (a probability is within 0..=1, a duration is a
//! positive finite number of seconds), so nonsense is refused with a clear message and exit
//! code 2 before anything runs. [`Cli::scenario`] turns it into a [`Scenario`].

use clap::{Parser, ValueEnum};
use flight_sitl::runner::cli::number_in;
use telemetry::channels::ChannelFormat;
use telemetry::link::{Band, RateMode};

use openlrs::BindingVersion;

use crate::handset::HandsetKind;
use crate::openlrs::OpenLrsScenario;
use crate::scenario::{Attack, Scenario};

/// The binding phrase of `--attack` runs without `--phrase`.
pub const ATTACK_PHRASE: &str = "taulink-sim attack";

/// Both TauLink ends (module master and flight follower, each on the real radio driver
/// driving a virtual Si4432) talking through a simulated RF medium in virtual time.
#[derive(Parser, Clone, Debug, PartialEq)]
#[command(
    name = "taulink-sim",
    version,
    // "--duration -5" is a value to refuse with a reason, not an unknown flag "-5".
    allow_negative_numbers = true,
    after_help = "Examples:
  taulink-sim                                      30 s at F250, 500 m, status line + table
  taulink-sim --rate F500 --loss 0.1 --foreign --json
  taulink-sim --cut 10:12 --duration 20 --plot out failsafe and recovery after a 2 s cut,
                                                   drawn to out/link.png
  taulink-sim --sweep                              every rate mode, clean and at 10 % loss
  taulink-sim --rate F700 --ratio 8 --handset ppm  the stick mode fed by free-running PPM
  taulink-sim --docs check                         the docs' link figures against a fresh
                                                   run (--docs write rewrites them)
  taulink-sim --serve                              the web ground station against the
                                                   firmware-in-the-loop world (flight-sitl
                                                   serve): open the printed URL
  taulink-sim --attack replay --json               a third radio replays every frame it
                                                   hears; JSON counts what was accepted
  taulink-sim --protocol openlrs38 --cut 10:12     the crate's OpenLRSng TX and RX roles
                                                   on the virtual chips (--olrs-profile,
                                                   --olrs-16ch), same figures

Exit status: 0 if every channel output and stream byte was right, 1 if any was wrong,
2 for a command-line error."
)]
pub struct Cli {
    /// Link protocol: taulink, or OpenLRSng (binding version 3.8 or 3.9: the crate's
    /// OpenLRSng TX role flying its RX role on the virtual chips; --olrs-profile and
    /// --olrs-16ch choose the air profile; TauLink-only options are refused).
    #[arg(long, value_enum, default_value_t = ProtocolArg::Taulink)]
    pub protocol: ProtocolArg,
    /// OpenLRSng modem profile: 0..=4 = 4800, 9600, 19200 (the default), 57600, 125000 bit/s.
    #[arg(long, value_name = "N", default_value_t = 2, value_parser = clap::value_parser!(u8).range(0..=4))]
    pub olrs_profile: u8,
    /// OpenLRSng: 16 channels per packet instead of 8.
    #[arg(long)]
    pub olrs_16ch: bool,
    /// Rate mode: L50 (long range), M100, F250, F500 (fast, short range) or F700 (the stick
    /// mode: sticks in every packet, aux channels round-robin; best at --ratio 8).
    #[arg(long, default_value_t = RateMode::F250)]
    pub rate: RateMode,
    /// Telemetry ratio: one downlink slot in N (a power of two, 2..=128).
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = ratio)]
    pub ratio: u8,
    /// Carry 8 channels per uplink instead of 16 (more room for uplink telemetry).
    #[arg(long)]
    pub compact8: bool,
    /// What feeds the module: crsf-synced (EdgeTX on CRSF at 400 kBd following the module's
    /// timing frames), crsf (EdgeTX ignoring them: every 4 ms of its own crystal), ppm
    /// (free-running 22.5 ms frames through the module's own PPM decoder), free-1k (a 1 kHz
    /// sample stream, the figures measured before handsets were modelled). Latency is from
    /// the handset's frame generation to the flight side's output (ppm: from the edge closing
    /// the frame's last channel, the decoder's 2.5 ms hold included).
    #[arg(long, value_enum, default_value_t = HandsetArg::CrsfSynced)]
    pub handset: HandsetArg,
    /// Frequency band in MHz.
    #[arg(long, value_enum, default_value_t = BandArg::Mhz433)]
    pub band: BandArg,
    /// Distance between module and flight controller, metres (0 < M ≤ 100000).
    #[arg(long, value_name = "M", default_value_t = 500.0, value_parser = distance)]
    pub distance: f64,
    /// Extra random packet loss, a probability 0..=1 (0.1 drops one packet in ten).
    #[arg(long, value_name = "P", default_value_t = 0.0, value_parser = probability)]
    pub loss: f64,
    /// Bit error rate on air, 0..=1 (packet-level medium only; selects it).
    #[arg(long, value_name = "P", default_value_t = 0.0, value_parser = probability)]
    pub ber: f64,
    /// Duty cycle 0..=1 of a jammer hopping in random bursts over the link's channel grid.
    #[arg(long, value_name = "DUTY", default_value_t = 0.0, value_parser = probability)]
    pub interference: f64,
    /// Run a second, independently bound link in the same medium.
    #[arg(long)]
    pub foreign: bool,
    /// Seed of every random choice (noise, loss, hopping, test data); same seed, same run.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed: u64,
    /// Virtual duration, seconds (0 < S ≤ 86400).
    #[arg(long, value_name = "S", default_value_t = 30.0, value_parser = duration)]
    pub duration: f64,
    /// Follower failsafe delay, milliseconds (1..=60000).
    #[arg(long, value_name = "MS", default_value_t = 250, value_parser = clap::value_parser!(u64).range(1..=60_000))]
    pub failsafe_ms: u64,
    /// Cut the path between the two ends from FROM to TO seconds of virtual time.
    #[arg(long, value_name = "FROM:TO", value_parser = cut)]
    pub cut: Option<(f64, f64)>,
    /// Start both ends bound (skip the over-the-air bind).
    #[arg(long)]
    pub no_bind: bool,
    /// Do not keep the telemetry streams saturated with test bytes.
    #[arg(long)]
    pub no_telemetry: bool,
    /// Turn the receivers' chip header check off (foreign packets then reach the link CRC).
    #[arg(long)]
    pub no_header_check: bool,
    /// Turn the receivers' chip CRC off (packet-level medium only; selects it).
    #[arg(long)]
    pub no_chip_crc: bool,
    /// Use the packet-level mock radios instead of the chip simulator (faster).
    #[arg(long)]
    pub packet_level: bool,
    /// Run every rate mode, clean and at 10 % loss, and print the comparison (with a
    /// progress bar on a terminal).
    #[arg(long, conflicts_with = "plot")]
    pub sweep: bool,
    /// The link figures the docs quote (README "Link figures", spec §10), from every rate
    /// mode at the default conditions (other options are ignored): print them, check the
    /// docs' `link-figures` blocks against them (exit 1 when stale), or write them.
    #[arg(long, value_enum, value_name = "MODE",
          conflicts_with_all = ["sweep", "serve", "json", "plot", "attack", "protocol"])]
    pub docs: Option<DocsArg>,
    /// `--plot DIR`: draw `link.png` (LQ, RSSI, updates/s, latency over time, cut and
    /// failsafe marked) into DIR.
    #[command(flatten)]
    pub plot: sim_plot::PlotArgs,
    /// Serve the web ground station against flight-sitl's firmware-in-the-loop world (both
    /// ends' applications, the quad flown by a scripted pilot; --rate, --seed and --loss
    /// apply) over HTTP and a WebSocket at ADDR (default 127.0.0.1:8018), in real time, and
    /// print the URL to open. Runs until interrupted.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8018",
          conflicts_with_all = ["sweep", "json"])]
    pub serve: Option<std::net::SocketAddr>,
    /// With --serve: the built app (default: telemetry/ground-station/dist in this checkout).
    #[arg(long, value_name = "DIR", requires = "serve")]
    pub dist: Option<std::path::PathBuf>,
    /// With --serve: virtual seconds per wall second (0.01..=100).
    #[arg(long, value_name = "X", default_value_t = 1.0, value_parser = speed)]
    pub speed: f64,
    /// Binding phrase the bind's key agreement runs on (CPace, as the firmware): the link is
    /// then keyed — every frame carries a tag, only frames of this link are accepted (spec
    /// §12). It must meet the phrase rule (12+ characters, 6 different, no famous example).
    #[arg(long, value_name = "TEXT", value_parser = phrase)]
    pub phrase: Option<String>,
    /// A keyed link without a phrase (the bind's anonymous key agreement).
    #[arg(long, conflicts_with = "phrase")]
    pub keyed: bool,
    /// A third radio in the medium, nearer the flight side, attacks the keyed link for the
    /// whole run (chip level): `forge` (knows the header and hop sequence, not the key),
    /// `replay` (records and re-sends every frame; the flight side is power-cycled twice),
    /// `bind-spoof` (bind offers without pause; the flight side is power-cycled every 5 s),
    /// `nonce-replay` (records the flight side's nonce frames, power-cycles it, then jams a
    /// downlink slot at the module and replays one in the next, again and again), `guess`
    /// (records the bind and the link, then tries every offline check of a dictionary that
    /// holds the true phrase; reports `offline_checkable`). The report adds the attacker's
    /// frames sent and accepted (must be 0).
    #[arg(long, value_enum, conflicts_with_all = ["sweep", "serve", "packet_level", "foreign", "ber", "no_chip_crc"])]
    pub attack: Option<AttackArg>,
    /// Dynamic transmit power (`telemetry::link::power`) on both ends, against the fixed
    /// maximum: with --walk, the walk is run both ways and compared.
    #[arg(long, requires = "walk")]
    pub dynamic_power: bool,
    /// With --dynamic-power: the flight side walks away from FROM to TO metres over
    /// --duration (geometrically; default 2000:200000, beyond the range at +20 dBm), the
    /// module core and the flight application at the ends on the chip simulator; prints each
    /// end's mean power and both LQs per tenth of the walk, fixed maximum against dynamic,
    /// and the power saved. Exit 1 when dynamic power lost LQ ≥ 95 % where the fixed
    /// maximum had it. --rate, --ratio, --seed and --duration apply; with --docs MODE the
    /// README's `dynamic-power` block from the documented walk (the defaults) instead.
    #[arg(long, value_name = "FROM:TO", num_args = 0..=1, default_missing_value = "2000:200000",
          value_parser = walk_range, requires = "dynamic_power",
          conflicts_with_all = ["sweep", "serve", "attack", "packet_level", "cut", "foreign", "plot", "protocol"])]
    pub walk: Option<(f64, f64)>,
    /// Print the report as JSON on stdout (fields in the README); no status line.
    #[arg(long)]
    pub json: bool,
    /// No status line or progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Link protocols as command-line words.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)] // the names are the documentation
pub enum ProtocolArg {
    #[value(name = "taulink")]
    Taulink,
    #[value(name = "openlrs38")]
    Openlrs38,
    #[value(name = "openlrs39")]
    Openlrs39,
}

/// `--docs`: what to do with the docs' generated link figures.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum DocsArg {
    /// Print both tables.
    Print,
    /// Fail (exit 1) when a document's table differs from the fresh run.
    Check,
    /// Rewrite the tables in the documents.
    Write,
}

impl From<DocsArg> for sim_plot::docblock::Mode {
    fn from(d: DocsArg) -> Self {
        match d {
            DocsArg::Print => Self::Print,
            DocsArg::Check => Self::Check,
            DocsArg::Write => Self::Write,
        }
    }
}

/// Handsets as command-line words.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)] // the names are the documentation
pub enum HandsetArg {
    #[value(name = "crsf-synced")]
    CrsfSynced,
    #[value(name = "crsf")]
    Crsf,
    #[value(name = "ppm")]
    Ppm,
    #[value(name = "free-1k")]
    Free1k,
}

impl From<HandsetArg> for HandsetKind {
    fn from(h: HandsetArg) -> Self {
        match h {
            HandsetArg::CrsfSynced => HandsetKind::CrsfSynced,
            HandsetArg::Crsf => HandsetKind::Crsf,
            HandsetArg::Ppm => HandsetKind::Ppm,
            HandsetArg::Free1k => HandsetKind::Free1k,
        }
    }
}

/// Attacks as command-line words.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AttackArg {
    /// Forged frames without the key.
    Forge,
    /// Recorded frames sent again.
    Replay,
    /// Bind offers while the flight side power-cycles.
    BindSpoof,
    /// Old nonce frames replayed after a jammed downlink slot.
    NonceReplay,
    /// Offline phrase guessing from a recording.
    Guess,
}

impl From<AttackArg> for Attack {
    fn from(a: AttackArg) -> Self {
        match a {
            AttackArg::Forge => Attack::Forge,
            AttackArg::Replay => Attack::Replay,
            AttackArg::BindSpoof => Attack::BindSpoof,
            AttackArg::NonceReplay => Attack::NonceReplay,
            AttackArg::Guess => Attack::Guess,
        }
    }
}

/// `--phrase`: the phrase rule every end applies.
fn phrase(text: &str) -> Result<String, String> {
    match telemetry::link::check_phrase(text) {
        Ok(Some(p)) => Ok(p.to_owned()),
        Ok(None) => Err("an empty phrase: leave --phrase out (or --keyed)".to_owned()),
        Err(e) => Err(e.to_string()),
    }
}

/// Bands as command-line words.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BandArg {
    /// 433 MHz ISM.
    #[value(name = "433")]
    Mhz433,
    /// 868 MHz SRD.
    #[value(name = "868")]
    Mhz868,
    /// 915 MHz ISM.
    #[value(name = "915")]
    Mhz915,
}

impl From<BandArg> for Band {
    fn from(b: BandArg) -> Self {
        match b {
            BandArg::Mhz433 => Band::Mhz433,
            BandArg::Mhz868 => Band::Mhz868,
            BandArg::Mhz915 => Band::Mhz915,
        }
    }
}

/// A real-time speed-up factor, 0.01..=100.
fn speed(text: &str) -> Result<f64, String> {
    number_in(text, 0.01, 100.0, "a speed-up factor")
}

fn probability(s: &str) -> Result<f64, String> {
    number_in(s, 0.0, 1.0, "a probability")
}

fn positive(s: &str, hi: f64, what: &str) -> Result<f64, String> {
    let v = number_in(s, 0.0, hi, what)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{what} must be greater than 0, got {s}"))
    }
}

fn distance(s: &str) -> Result<f64, String> {
    positive(s, 100_000.0, "the distance (m)")
}

fn duration(s: &str) -> Result<f64, String> {
    positive(s, 86_400.0, "the duration (s)")
}

fn ratio(s: &str) -> Result<u8, String> {
    let v: u8 = s
        .parse()
        .map_err(|_| format!("{s:?} is not a whole number 2..=128"))?;
    if telemetry::frame::valid_telemetry_ratio(v) {
        Ok(v)
    } else {
        Err(format!(
            "the ratio must be a power of two, 2..=128, got {v}"
        ))
    }
}

fn cut(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("{s:?}: expected FROM:TO in seconds, e.g. 10:12"))?;
    let from = number_in(a, 0.0, 86_400.0, "FROM (s)")?;
    let to = number_in(b, 0.0, 86_400.0, "TO (s)")?;
    if to <= from {
        return Err(format!("the cut must end after it starts, got {s}"));
    }
    Ok((from, to))
}

fn walk_range(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("{s:?}: expected FROM:TO in metres, e.g. 2000:200000"))?;
    let from = number_in(a, 1.0, 1_000_000.0, "FROM (m)")?;
    let to = number_in(b, 1.0, 1_000_000.0, "TO (m)")?;
    if to <= from {
        return Err(format!("the walk must go away from the module, got {s}"));
    }
    Ok((from, to))
}

impl Cli {
    /// The walk `--dynamic-power --walk` asks for, if it does.
    pub fn walk_plan(&self) -> Option<crate::walk::WalkPlan> {
        let (from_m, to_m) = self.walk.filter(|_| self.dynamic_power)?;
        Some(crate::walk::WalkPlan {
            rate: self.rate,
            ratio: self.ratio,
            from_m,
            to_m,
            duration_s: self.duration,
            bins: crate::walk::WALK_BINS,
            seed: self.seed,
        })
    }

    /// The OpenLRSng scenario these options describe: `Ok(None)` for `--protocol taulink`,
    /// an error naming the first option that has no meaning for OpenLRSng (the TauLink
    /// rate, keying, attacks, handset models, packet-level medium, sweeps, plots, serve).
    pub fn openlrs(&self) -> Result<Option<OpenLrsScenario>, String> {
        let version = match self.protocol {
            ProtocolArg::Taulink => {
                if self.olrs_profile != 2 || self.olrs_16ch {
                    return Err(
                        "--olrs-profile and --olrs-16ch need --protocol openlrs38|openlrs39".into(),
                    );
                }
                return Ok(None);
            }
            ProtocolArg::Openlrs38 => BindingVersion::V38,
            ProtocolArg::Openlrs39 => BindingVersion::V39,
        };
        let refused = [
            (
                self.rate != RateMode::F250,
                "--rate (OpenLRSng: --olrs-profile)",
            ),
            (self.ratio != 4, "--ratio"),
            (
                self.compact8,
                "--compact8 (OpenLRSng carries 8 channels unless --olrs-16ch)",
            ),
            (self.handset != HandsetArg::CrsfSynced, "--handset"),
            (self.band != BandArg::Mhz433, "--band"),
            (self.ber > 0.0, "--ber"),
            (self.interference > 0.0, "--interference"),
            (self.foreign, "--foreign"),
            (
                self.failsafe_ms != 250,
                "--failsafe-ms (OpenLRSng's failsafe delay is in its bind data)",
            ),
            (self.no_bind, "--no-bind"),
            (self.no_telemetry, "--no-telemetry"),
            (self.no_header_check, "--no-header-check"),
            (self.no_chip_crc, "--no-chip-crc"),
            (self.packet_level, "--packet-level"),
            (self.sweep, "--sweep"),
            (self.plot.plot.is_some(), "--plot"),
            (self.serve.is_some(), "--serve"),
            (
                self.phrase.is_some(),
                "--phrase (OpenLRSng frames carry no key)",
            ),
            (self.attack.is_some(), "--attack"),
        ];
        if let Some((_, name)) = refused.iter().find(|(given, _)| *given) {
            return Err(format!(
                "{name} has no meaning with --protocol openlrs38|openlrs39"
            ));
        }
        Ok(Some(OpenLrsScenario {
            version,
            modem_profile: self.olrs_profile,
            sixteen_channels: self.olrs_16ch,
            distance_m: self.distance,
            loss: self.loss,
            seed: self.seed,
            duration_s: self.duration,
            cut_s: self.cut,
        }))
    }

    /// The scenario these options describe. Injected bit errors and a disabled chip CRC
    /// exist only in the packet-level medium (the chip simulator derives bit errors from
    /// the signal-to-noise ratio), so either selects it.
    #[must_use]
    pub fn scenario(&self) -> Scenario {
        let attack: Option<Attack> = self.attack.map(Into::into);
        // An attacked link runs keyed (the default phrase if none is given).
        let phrase = self
            .phrase
            .clone()
            .or(attack.map(|_| ATTACK_PHRASE.to_owned()));
        let keyed = phrase.is_some() || self.keyed;
        // Stream test bytes are checked end to end; a power-cycled flight side loses its
        // stream buffers, so runs that power-cycle it carry none.
        let cycles_power = matches!(
            attack,
            Some(Attack::Replay | Attack::BindSpoof | Attack::NonceReplay)
        );
        let rate = self.rate;
        let format = if self.compact8 {
            ChannelFormat::Compact8
        } else {
            ChannelFormat::Full16
        };
        Scenario {
            rate,
            telemetry_ratio: self.ratio,
            // F700 carries 16 channels in its stick format.
            format: telemetry::link::bind::format_for(rate, format),
            band: self.band.into(),
            distance_m: self.distance,
            loss: self.loss,
            bit_error_rate: self.ber,
            interference: self.interference,
            foreign_link: self.foreign,
            seed: self.seed,
            duration_s: self.duration,
            failsafe_ms: self.failsafe_ms,
            cut_s: self.cut,
            // An attacked link was bound before the run — but for the guesser, who records
            // the bind.
            bind: !self.no_bind && matches!(attack, None | Some(Attack::Guess)),
            telemetry_load: !self.no_telemetry && !cycles_power,
            header_check: !self.no_header_check,
            chip_crc: !self.no_chip_crc,
            chip_level: !self.packet_level && self.ber == 0.0 && !self.no_chip_crc,
            key: keyed.then(|| crate::scenario::link_key_of(self.seed)),
            phrase,
            attack,
            silent_attacker: false,
            handset: self.handset.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("taulink-sim").chain(s.split_whitespace()))
    }

    #[test]
    fn parses_options() {
        let c = parse("--rate f500 --ratio 8 --loss 0.1 --cut 2:3.5 --foreign --json").unwrap();
        let s = c.scenario();
        assert_eq!(s.rate, RateMode::F500);
        assert_eq!(s.telemetry_ratio, 8);
        assert_eq!(s.loss, 0.1);
        assert_eq!(s.cut_s, Some((2.0, 3.5)));
        assert!(s.foreign_link && c.json && s.chip_level);
        assert!(!parse("--ber 0.001").unwrap().scenario().chip_level);
    }

    #[test]
    fn an_attack_runs_keyed_at_chip_level() {
        let s = parse("--attack bind-spoof").unwrap().scenario();
        assert_eq!(s.attack, Some(Attack::BindSpoof));
        assert_eq!(s.phrase.as_deref(), Some(ATTACK_PHRASE));
        assert_eq!(s.key, Some(crate::scenario::link_key_of(1)));
        assert!(s.chip_level && !s.telemetry_load && !s.bind);
        let s = parse("--attack forge --phrase brass-lantern-weir")
            .unwrap()
            .scenario();
        assert_eq!(s.phrase.as_deref(), Some("brass-lantern-weir"));
        assert!(s.telemetry_load && s.key.is_some());
        let s = parse("--attack guess").unwrap().scenario();
        assert!(s.bind, "the guesser records the bind");
        assert_eq!(parse("--keyed").unwrap().scenario().phrase, None);
        assert!(parse("--keyed").unwrap().scenario().key.is_some());
        assert!(parse("--phrase x").is_err(), "the phrase rule");
    }

    #[test]
    fn defaults_are_the_scenario_defaults() {
        let d = Scenario::default();
        let s = parse("").unwrap().scenario();
        assert_eq!(format!("{s:?}"), format!("{d:?}"));
    }

    #[test]
    fn refuses_nonsense() {
        for bad in [
            "--ratio 3",
            "--loss 2",
            "--loss -0.1",
            "--loss nan",
            "--duration -5",
            "--duration nan",
            "--duration 0",
            "--duration inf",
            "--distance nan",
            "--distance -1",
            "--cut 5:2",
            "--cut 5",
            "--failsafe-ms 0",
            "--band 2400",
            "--rate F1000",
            "--handset sbus",
            "--bogus",
            "--attack jam",
            "--attack forge --sweep",
            "--docs check --sweep",
            "--docs check --json",
            "--docs stale",
            "--attack replay --packet-level",
        ] {
            assert!(parse(bad).is_err(), "{bad} accepted");
        }
    }
}
