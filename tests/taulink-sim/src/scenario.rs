//! What to simulate: one struct of knobs with the main job's defaults, and its command-line
//! parser.

use telemetry::channels::ChannelFormat;
use telemetry::link::{Band, RateMode};

/// A simulation scenario.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Rate mode of the link.
    pub rate: RateMode,
    /// One slot in this many is a downlink slot.
    pub telemetry_ratio: u8,
    /// Uplink channel format.
    pub format: ChannelFormat,
    /// Band.
    pub band: Band,
    /// Distance between module and flight controller, metres.
    pub distance_m: f64,
    /// Extra random packet loss (0..1).
    pub loss: f64,
    /// Bit error rate on air.
    pub bit_error_rate: f64,
    /// Duty cycle (0..1) of a jammer hopping over the link's channel grid.
    pub interference: f64,
    /// Run a second, independently bound link in the same medium.
    pub foreign_link: bool,
    /// Seed of every random choice.
    pub seed: u64,
    /// Virtual duration, seconds.
    pub duration_s: f64,
    /// Follower failsafe delay, ms.
    pub failsafe_ms: u64,
    /// Cut the path between the two ends from..to (virtual seconds).
    pub cut_s: Option<(f64, f64)>,
    /// Over-the-air bind first (otherwise both ends start bound).
    pub bind: bool,
    /// Keep both telemetry streams saturated with test bytes.
    pub telemetry_load: bool,
    /// Chip header check on the receivers (off exposes foreign packets to the link CRC).
    pub header_check: bool,
    /// Chip CRC on the receivers (off exposes corrupted packets to the link CRC; packet
    /// level only).
    pub chip_crc: bool,
    /// Run the real RFM22b driver on virtual Si4432s (`si4432-sim`); otherwise the
    /// packet-level mock radios (faster; supports `bit_error_rate` and `chip_crc`).
    pub chip_level: bool,
}

impl Default for Scenario {
    fn default() -> Self {
        Self {
            rate: RateMode::F250,
            telemetry_ratio: 4,
            format: ChannelFormat::Full16,
            band: Band::Mhz433,
            distance_m: 500.0,
            loss: 0.0,
            bit_error_rate: 0.0,
            interference: 0.0,
            foreign_link: false,
            seed: 1,
            duration_s: 30.0,
            failsafe_ms: 250,
            cut_s: None,
            bind: true,
            telemetry_load: true,
            header_check: true,
            chip_crc: true,
            chip_level: true,
        }
    }
}

/// Parses a rate mode name (`L50`, `M100`, `F250`, `F500`, case-insensitive).
pub fn parse_rate(s: &str) -> Option<RateMode> {
    RateMode::ALL
        .into_iter()
        .find(|m| format!("{m:?}").eq_ignore_ascii_case(s))
}

/// Command-line options besides the scenario.
#[derive(Clone, Debug, Default)]
pub struct Output {
    /// Print JSON instead of the table.
    pub json: bool,
    /// No live status line.
    pub quiet: bool,
    /// Run every rate mode (clean and at 10 % loss) and print the comparison table.
    pub sweep: bool,
}

/// The usage text.
pub const USAGE: &str =
    "taulink-sim [--rate L50|M100|F250|F500] [--ratio N] [--compact8] [--band 433|868|915]
            [--distance M] [--loss P] [--ber P] [--interference DUTY] [--foreign]
            [--seed N] [--duration S] [--failsafe-ms MS] [--cut FROM:TO] [--no-bind]
            [--no-telemetry] [--no-header-check] [--no-chip-crc] [--packet-level]
            [--json] [--quiet] [--sweep]";

/// Parses command-line arguments (without the program name).
pub fn parse_args(args: &[String]) -> Result<(Scenario, Output), String> {
    let mut s = Scenario::default();
    let mut out = Output::default();
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{name} needs a value"))
        };
        let num = |v: String| v.parse::<f64>().map_err(|e| format!("{v}: {e}"));
        match arg.as_str() {
            "--rate" => {
                let v = value("--rate")?;
                s.rate = parse_rate(&v).ok_or_else(|| format!("unknown rate {v}"))?;
            }
            "--ratio" => {
                let v = value("--ratio")?;
                s.telemetry_ratio = v.parse().map_err(|e| format!("{v}: {e}"))?;
                if !telemetry::frame::valid_telemetry_ratio(s.telemetry_ratio) {
                    return Err("--ratio must be a power of two, 2..=128".into());
                }
            }
            "--compact8" => s.format = ChannelFormat::Compact8,
            "--band" => {
                s.band = match value("--band")?.as_str() {
                    "433" => Band::Mhz433,
                    "868" => Band::Mhz868,
                    "915" => Band::Mhz915,
                    other => return Err(format!("unknown band {other}")),
                }
            }
            "--distance" => s.distance_m = num(value("--distance")?)?,
            "--loss" => s.loss = num(value("--loss")?)?,
            "--ber" => s.bit_error_rate = num(value("--ber")?)?,
            "--interference" => s.interference = num(value("--interference")?)?,
            "--foreign" => s.foreign_link = true,
            "--seed" => s.seed = num(value("--seed")?)? as u64,
            "--duration" => s.duration_s = num(value("--duration")?)?,
            "--failsafe-ms" => s.failsafe_ms = num(value("--failsafe-ms")?)? as u64,
            "--cut" => {
                let v = value("--cut")?;
                let (a, b) = v.split_once(':').ok_or("--cut FROM:TO")?;
                s.cut_s = Some((num(a.into())?, num(b.into())?));
            }
            "--no-bind" => s.bind = false,
            "--no-telemetry" => s.telemetry_load = false,
            "--no-header-check" => s.header_check = false,
            "--no-chip-crc" => s.chip_crc = false,
            "--packet-level" => s.chip_level = false,
            "--json" => out.json = true,
            "--quiet" => out.quiet = true,
            "--sweep" => out.sweep = true,
            "-h" | "--help" => return Err(USAGE.into()),
            other => return Err(format!("unknown option {other}\n{USAGE}")),
        }
    }
    // Injected bit errors and a disabled chip CRC exist only in the packet-level medium
    // (the chip simulator derives bit errors from the signal-to-noise ratio).
    if s.bit_error_rate > 0.0 || !s.chip_crc {
        s.chip_level = false;
    }
    Ok((s, out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_options() {
        let args: Vec<String> = "--rate f500 --ratio 8 --loss 0.1 --cut 2:3.5 --foreign --json"
            .split(' ')
            .map(String::from)
            .collect();
        let (s, o) = parse_args(&args).unwrap();
        assert_eq!(s.rate, RateMode::F500);
        assert_eq!(s.telemetry_ratio, 8);
        assert_eq!(s.loss, 0.1);
        assert_eq!(s.cut_s, Some((2.0, 3.5)));
        assert!(s.foreign_link && o.json);
        assert!(parse_args(&["--ratio".into(), "3".into()]).is_err());
        assert!(parse_args(&["--bogus".into()]).is_err());
    }
}
