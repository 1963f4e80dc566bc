//! Instruction figures in the docs, generated: `cargo xtask figures` builds the m4-bench
//! programs, counts each one's regions with m4count under QEMU, names the figures the docs
//! quote (the table below), and checks (`--check`) or rewrites (`--write`) every number that
//! follows a `<!-- m4:NAME -->` marker in the project's Markdown files. A doc figure without a
//! marker is a historical one ("before", "was"); a current one always has its marker, so no
//! hand-copied count can go stale unnoticed.
//!
//! Some figures are budgets as well ([`BUDGETS`]): `--check` also fails when one of them is
//! over its limit, so a change that makes the flight loop too slow fails CI rather than
//! just updating the docs.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::{env, fs};

/// How a figure is computed from one bench's region counts (1-based, as m4count prints).
#[derive(Debug, Clone, Copy)]
enum Select {
    /// One region.
    Region(usize),
    /// One region divided by a repetition count (a mean over N steps), rounded.
    Mean(usize, u64),
    /// The largest of an inclusive range of regions.
    Max(usize, usize),
    /// A per-slot figure of the `link` bench (see [`link_figure`]).
    Link(LinkFigure),
}

/// Which slots, which end and which part of the `link` bench's five regions per slot.
#[derive(Debug, Clone, Copy)]
struct LinkFigure {
    uplink: bool,
    /// Regions of a slot summed (0-based within the slot's five).
    parts: &'static [usize],
    stat: Stat,
}

#[derive(Debug, Clone, Copy)]
enum Stat {
    Min,
    Mean,
    Max,
}

/// Every figure the docs may quote: name, bench, selection. The benches' `//!` comments say
/// what each region measures.
const FIGURES: &[(&str, &str, Select)] = &[
    ("auth.uplink_tag", "auth", Select::Region(1)),
    ("auth.uplink_check", "auth", Select::Region(3)),
    ("auth.downlink_tag", "auth", Select::Region(5)),
    ("auth.link_crc", "auth", Select::Region(7)),
    ("auth.nonce_tag", "auth", Select::Region(9)),
    ("auth.epoch_key", "auth", Select::Region(11)),
    ("pake.start", "pake", Select::Region(1)),
    ("pake.finish", "pake", Select::Region(3)),
    ("pake.iteration", "pake", Select::Mean(5, 16)),
    ("loop.design", "flight_loop", Select::Region(1)),
    ("loop.attitude", "flight_loop", Select::Region(3)),
    ("loop.rate_pid", "flight_loop", Select::Region(5)),
    ("loop.rate_lqg", "flight_loop", Select::Region(7)),
    ("loop.attitude_mean20", "flight_loop", Select::Mean(9, 20)),
    ("loop.sysid", "flight_loop", Select::Region(11)),
    ("loop.attitude_worst", "flight_loop", Select::Max(13, 32)),
    ("loop.ins", "flight_loop", Select::Region(34)),
    ("loop.ins_baro", "flight_loop", Select::Region(36)),
    ("loop.ins_mean100", "flight_loop", Select::Mean(38, 100)),
    ("app.new", "flight_app", Select::Region(1)),
    ("app.imu_sample", "flight_app", Select::Region(3)),
    ("app.loop_step", "flight_app", Select::Region(5)),
    ("app.imu_missing", "flight_app", Select::Region(7)),
    ("app.imu_sample_log_off", "flight_app", Select::Mean(9, 10)),
    (
        "app.imu_sample_log_full",
        "flight_app",
        Select::Mean(11, 10),
    ),
    ("control.design", "control", Select::Region(1)),
    ("control.lqg", "control", Select::Region(3)),
    ("control.pid", "control", Select::Region(5)),
    ("control.sysid_ekf", "control", Select::Region(7)),
    ("ins.predict", "ins", Select::Region(1)),
    ("ins.gps_position", "ins", Select::Region(2)),
    ("ins.gps_velocity", "ins", Select::Region(3)),
    ("ins.baro", "ins", Select::Region(4)),
    ("ins.mag", "ins", Select::Region(5)),
    ("ins.full", "ins", Select::Region(6)),
    ("gps.parse", "gps", Select::Region(1)),
    ("gps.fuse", "gps", Select::Region(2)),
    ("radio.modem_config", "radio", Select::Region(1)),
    ("radio.init", "radio", Select::Region(3)),
    ("radio.send16", "radio", Select::Region(5)),
    ("radio.receive16", "radio", Select::Region(7)),
    ("radio.send29", "radio", Select::Region(9)),
    ("radio.receive29", "radio", Select::Region(11)),
    ("radio.send34", "radio", Select::Region(13)),
    ("radio.receive34", "radio", Select::Region(15)),
    link("link.up.master_plan", true, &[0]),
    link("link.up.master_sent", true, &[2]),
    link("link.up.follower_plan", true, &[1]),
    link("link.up.follower_received", true, &[3]),
    link("link.down.master_plan", false, &[0]),
    link("link.down.master_received", false, &[2]),
    link("link.down.follower_plan", false, &[1]),
    link("link.down.follower_sent", false, &[3]),
    link("link.up.master", true, &[0, 2]),
    link("link.up.follower", true, &[1, 3]),
    link("link.down.master", false, &[0, 2]),
    link("link.down.follower", false, &[1, 3]),
];

/// Upper limits on figures (name, the most instructions allowed), checked by `--check`.
/// - `loop.attitude` ≤ 1 200: issue 17's goal for one full flight-loop step in attitude
///   mode (≈ 9 µs at CPI 1.3 on the 168 MHz F405, ≈ 7 % of the CPU at 8 kHz).
/// - `link.up.master.max` ≤ 4 500: issue 33's limit on the master's worst slot (an uplink:
///   its length counted, its frame built once after the late latch, `on_sent`), ≈ 91 µs on
///   the module's 64 MHz nRF52840 at CPI 1.3 — the frame must be built and in the FIFO
///   within the 209 µs of preamble and sync F700 leaves after the latch (spec §10).
/// - `loop.ins` ≤ 3 500: issue 33's goal for a flight-loop step with the INS predicting
///   (≈ 27 µs at CPI 1.3, 2.7 % of the CPU at 1 kHz; the Tau Labs C INS's predict alone is
///   5 540, `../shared/reference/ekf.md` §10).
/// - `ins.full` ≤ 8 000: issue 33's goal for the full correction — GPS position and
///   velocity, baro and magnetometer in one step (the C INS's 10-row correction: 30 838).
pub const BUDGETS: &[(&str, u64)] = &[
    ("loop.attitude", 1_200),
    ("loop.ins", 3_500),
    ("ins.full", 8_000),
    ("link.up.master.max", 4_500),
];

/// The budgets a set of figure values breaks: (name, value, limit).
fn over_budget(
    value: impl Fn(&str) -> Result<u64, String>,
) -> Result<Vec<(&'static str, u64, u64)>, String> {
    let mut over = Vec::new();
    for &(name, limit) in BUDGETS {
        let v = value(name)?;
        if v > limit {
            over.push((name, v, limit));
        }
    }
    Ok(over)
}

/// A `link` figure; the statistic is chosen by the suffix the doc's marker adds
/// (`.min`, `.mean`, `.max`), so one table row names its three numbers.
const fn link(
    name: &'static str,
    uplink: bool,
    parts: &'static [usize],
) -> (&'static str, &'static str, Select) {
    (
        name,
        "link",
        Select::Link(LinkFigure {
            uplink,
            parts,
            stat: Stat::Max,
        }),
    )
}

/// The link bench's slot statistics. Each slot is five regions (master plan, follower plan,
/// master completion, follower completion, setup); an uplink slot is one where the master
/// builds a frame, i.e. its plan is the longer of the two plans.
fn link_figure(regions: &[u64], f: LinkFigure) -> Option<u64> {
    let values: Vec<u64> = regions
        .chunks_exact(5)
        .filter(|s| (s.first() > s.get(1)) == f.uplink)
        .map(|s| f.parts.iter().filter_map(|&i| s.get(i)).sum())
        .collect();
    let n = u64::try_from(values.len()).ok().filter(|&n| n > 0)?;
    Some(match f.stat {
        Stat::Min => *values.iter().min()?,
        Stat::Max => *values.iter().max()?,
        Stat::Mean => (values.iter().sum::<u64>() + n / 2) / n,
    })
}

fn select(regions: &[u64], s: Select) -> Option<u64> {
    let r = |i: usize| regions.get(i.checked_sub(1)?).copied();
    match s {
        Select::Region(i) => r(i),
        Select::Mean(i, n) => r(i).map(|v| (v + n / 2) / n),
        Select::Max(a, b) => (a..=b)
            .map(r)
            .collect::<Option<Vec<_>>>()?
            .into_iter()
            .max(),
        Select::Link(f) => link_figure(regions, f),
    }
}

/// Looks a marker's name up: a table name, or a link name with `.min` / `.mean` / `.max`.
fn lookup(name: &str) -> Option<(&'static str, Select)> {
    if let Some(&(_, bench, s)) = FIGURES.iter().find(|(n, _, _)| *n == name) {
        return Some((bench, s));
    }
    let (base, stat) = name.rsplit_once('.')?;
    let stat = match stat {
        "min" => Stat::Min,
        "mean" => Stat::Mean,
        "max" => Stat::Max,
        _ => return None,
    };
    match FIGURES.iter().find(|(n, _, _)| *n == base)? {
        &(_, bench, Select::Link(f)) => Some((bench, Select::Link(LinkFigure { stat, ..f }))),
        _ => None,
    }
}

/// The project's number format: thousands grouped by a space ("5 442 348").
pub fn format(v: u64) -> String {
    let digits = v.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

const MARKER_OPEN: &str = "<!-- m4:";
const MARKER_CLOSE: &str = " -->";

/// One marked figure in a document: its name and the byte range of the number after it.
#[derive(Debug, PartialEq)]
pub struct Mark {
    pub name: String,
    pub number: std::ops::Range<usize>,
}

/// Every marker of a document with the number that follows it; an error names a marker
/// without a number right after it.
pub fn marks(text: &str) -> Result<Vec<Mark>, String> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(at) = text.get(from..).and_then(|t| t.find(MARKER_OPEN)) {
        let name_start = from + at + MARKER_OPEN.len();
        let rest = text.get(name_start..).unwrap_or_default();
        let close = rest
            .find(MARKER_CLOSE)
            .ok_or_else(|| format!("unclosed marker at byte {}", from + at))?;
        let name = rest.get(..close).unwrap_or_default().trim().to_string();
        let start = name_start + close + MARKER_CLOSE.len();
        // Prose that shows the syntax (`<!-- m4:NAME -->`) is not a marker: names are
        // lower case, digits, `_` and `.`.
        if name.is_empty()
            || !name
                .bytes()
                .all(|c| matches!(c, b'a'..=b'z' | b'0'..=b'9' | b'_' | b'.'))
        {
            from = start;
            continue;
        }
        let len = number_len(text.get(start..).unwrap_or_default());
        if len == 0 {
            return Err(format!("marker `{name}` is not followed by a number"));
        }
        out.push(Mark {
            name,
            number: start..start + len,
        });
        from = start + len;
    }
    Ok(out)
}

/// Length of a number in the project's format at the start of `s`: 1–3 digits, then groups
/// of a space and three digits.
fn number_len(s: &str) -> usize {
    let b = s.as_bytes();
    let lead = b.iter().take_while(|c| c.is_ascii_digit()).count();
    if lead == 0 || lead > 3 {
        // No number, or one written without grouping: all of its digits.
        return lead;
    }
    let mut len = lead;
    while b.get(len) == Some(&b' ')
        && b.get(len + 1..len + 4)
            .is_some_and(|g| g.iter().all(u8::is_ascii_digit))
        && !b.get(len + 4).is_some_and(u8::is_ascii_digit)
    {
        len += 4;
    }
    len
}

/// The Markdown files that may carry markers: every tracked `.md` outside dependencies.
fn documents(root: &Path) -> Result<Vec<PathBuf>, String> {
    let out = Command::new("git")
        .current_dir(root)
        .args(["ls-files", "*.md"])
        .output()
        .map_err(|e| format!("cannot run git: {e}"))?;
    if !out.status.success() {
        return Err("git ls-files failed".into());
    }
    // A file in conflict is listed once per index stage: once is enough.
    let mut files: Vec<PathBuf> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.contains("node_modules/"))
        .map(|l| root.join(l))
        .collect();
    files.dedup();
    Ok(files)
}

/// Where m4count is: `$M4COUNT`, or `../shared/tools/m4count/m4count` beside the checkout.
fn m4count(root: &Path) -> Result<PathBuf, String> {
    let path = env::var_os("M4COUNT")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("../shared/tools/m4count/m4count"));
    if path.is_file() {
        Ok(path)
    } else {
        Err(format!(
            "m4count not found at {} (set M4COUNT); it needs qemu-system-arm and a C compiler",
            path.display()
        ))
    }
}

/// Counts one bench's regions.
fn regions(m4count: &Path, elf: &Path) -> Result<Vec<u64>, String> {
    let out = Command::new(m4count)
        .arg(elf)
        .output()
        .map_err(|e| format!("cannot run {}: {e}", m4count.display()))?;
    if !out.status.success() {
        return Err(format!(
            "{} failed on {} (a bench exits non-zero when a result it checks is wrong):\n{}",
            m4count.display(),
            elf.display(),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(parse_regions(&String::from_utf8_lossy(&out.stdout)))
}

/// The counts of m4count's `region N: X instructions` lines, in order.
pub fn parse_regions(output: &str) -> Vec<u64> {
    output
        .lines()
        .filter_map(|l| l.strip_prefix("region "))
        .filter_map(|l| l.split_whitespace().nth(1)?.parse().ok())
        .collect()
}

/// What `cargo xtask figures` does with the docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    /// Print every figure.
    Print,
    /// Fail when a marked figure differs.
    Check,
    /// Rewrite every marked figure.
    Write,
}

pub fn run(root: &Path, elf_dir: &Path, mode: Mode) -> Result<(), String> {
    let m4count = m4count(root)?;
    let mut counts: BTreeMap<&str, Vec<u64>> = BTreeMap::new();
    for bench in FIGURES.iter().map(|(_, b, _)| *b) {
        if !counts.contains_key(bench) {
            counts.insert(bench, regions(&m4count, &elf_dir.join(bench))?);
        }
    }
    let value = |name: &str| -> Result<u64, String> {
        let (bench, s) = lookup(name).ok_or_else(|| format!("unknown figure `{name}`"))?;
        let regions = counts.get(bench).map(Vec::as_slice).unwrap_or_default();
        select(regions, s)
            .ok_or_else(|| format!("figure `{name}`: bench `{bench}` has too few regions"))
    };
    let over = over_budget(value)?;
    for (name, v, limit) in &over {
        println!(
            "OVER BUDGET {name}: {} instructions, the limit is {}",
            format(*v),
            format(*limit)
        );
    }
    if mode == Mode::Print {
        for (name, _, s) in FIGURES {
            match s {
                Select::Link(_) => {
                    let [min, mean, max] =
                        [".min", ".mean", ".max"].map(|x| value(&format!("{name}{x}")));
                    println!("{name:<28} {} / {} / {}", min?, mean?, max?);
                }
                _ => println!("{name:<28} {}", value(name)?),
            }
        }
        return Ok(());
    }
    let mut stale = 0;
    let mut seen = 0;
    // Every document is checked before any is written, so an error leaves all untouched.
    let mut rewrites = Vec::new();
    for doc in documents(root)? {
        let text = fs::read_to_string(&doc).map_err(|e| format!("{}: {e}", doc.display()))?;
        let marks = marks(&text).map_err(|e| format!("{}: {e}", doc.display()))?;
        if marks.is_empty() {
            continue;
        }
        let shown = doc.strip_prefix(root).unwrap_or(&doc).display().to_string();
        let mut new = String::new();
        let mut last = 0;
        for m in &marks {
            seen += 1;
            let want = format(value(&m.name).map_err(|e| format!("{shown}: {e}"))?);
            let have = text.get(m.number.clone()).unwrap_or_default();
            if have != want {
                stale += 1;
                println!(
                    "{} {shown}: {} is {want}, the doc says {have}",
                    if mode == Mode::Check {
                        "STALE"
                    } else {
                        "write"
                    },
                    m.name
                );
            }
            new.push_str(text.get(last..m.number.start).unwrap_or_default());
            new.push_str(&want);
            last = m.number.end;
        }
        new.push_str(text.get(last..).unwrap_or_default());
        if new != text {
            rewrites.push((doc, new));
        }
    }
    if mode == Mode::Write {
        for (doc, new) in rewrites {
            fs::write(&doc, new).map_err(|e| format!("{}: {e}", doc.display()))?;
        }
    }
    println!(
        "{seen} marked figures, {stale} {}",
        if mode == Mode::Write {
            "rewritten"
        } else {
            "stale"
        }
    );
    if mode == Mode::Check && stale > 0 {
        return Err(format!(
            "{stale} figure(s) in the docs are stale: run `cargo xtask figures --write`"
        ));
    }
    if mode == Mode::Check && !over.is_empty() {
        return Err(format!(
            "{} figure(s) over their budget (`figures::BUDGETS`)",
            over.len()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_grouped_by_spaces() {
        assert_eq!(format(7), "7");
        assert_eq!(format(1248), "1 248");
        assert_eq!(format(5_442_348), "5 442 348");
        assert_eq!(format(100_000), "100 000");
    }

    #[test]
    fn markers_find_the_number_after_them() {
        let text = "step **<!-- m4:loop.attitude -->1 248** and <!-- m4:auth.link_crc -->304 per frame, 5 123 more";
        let m = marks(text).unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].name, "loop.attitude");
        assert_eq!(&text[m[0].number.clone()], "1 248");
        assert_eq!(&text[m[1].number.clone()], "304");
    }

    #[test]
    fn a_number_ends_at_a_group_that_is_not_three_digits() {
        assert_eq!(number_len("1 248 with"), 5);
        assert_eq!(number_len("17 231 × 1.3"), 6);
        assert_eq!(number_len("73. And"), 2);
        assert_eq!(number_len("1 2345"), 1);
        assert_eq!(number_len("x"), 0);
    }

    #[test]
    fn the_syntax_shown_in_prose_is_not_a_marker() {
        let m =
            marks("a figure after `<!-- m4:NAME -->` is rewritten; <!-- m4:auth.link_crc -->304")
                .unwrap();
        assert_eq!(m.len(), 1);
        assert_eq!(m[0].name, "auth.link_crc");
    }

    #[test]
    fn a_marker_without_a_number_is_an_error() {
        assert!(marks("<!-- m4:loop.attitude --> about 1 200").is_err());
        assert!(marks("<!-- m4:loop.attitude").is_err());
    }

    #[test]
    fn every_figure_name_resolves_and_link_names_take_a_statistic() {
        for (name, _, s) in FIGURES {
            match s {
                Select::Link(_) => {
                    for x in [".min", ".mean", ".max"] {
                        assert!(lookup(&format!("{name}{x}")).is_some(), "{name}{x}");
                    }
                }
                _ => assert!(lookup(name).is_some(), "{name}"),
            }
        }
        assert!(lookup("loop.attitude.max").is_none());
        assert!(lookup("nothing").is_none());
    }

    #[test]
    fn link_slots_are_told_apart_by_the_longer_plan() {
        // Two uplink slots (master plan longer) and one downlink slot.
        let regions = [
            3400, 120, 99, 3500, 10, 3600, 130, 99, 3700, 10, 45, 1400, 1230, 70, 10,
        ];
        let up = |parts, stat| {
            link_figure(
                &regions,
                LinkFigure {
                    uplink: true,
                    parts,
                    stat,
                },
            )
        };
        assert_eq!(up(&[0], Stat::Min), Some(3400));
        assert_eq!(up(&[0], Stat::Mean), Some(3500));
        assert_eq!(up(&[1, 3], Stat::Max), Some(3830));
        let down = link_figure(
            &regions,
            LinkFigure {
                uplink: false,
                parts: &[0, 2],
                stat: Stat::Max,
            },
        );
        assert_eq!(down, Some(1275));
    }

    #[test]
    fn a_figure_over_its_budget_is_reported_and_one_within_is_not() {
        for &(name, limit) in BUDGETS {
            assert!(lookup(name).is_some(), "budget for unknown figure {name}");
            let at = over_budget(|n| Ok(if n == name { limit } else { 0 })).unwrap();
            assert!(at.is_empty(), "{name} at its limit is within budget");
            let above = over_budget(|n| Ok(if n == name { limit + 1 } else { 0 })).unwrap();
            assert_eq!(above, vec![(name, limit + 1, limit)]);
        }
        for (name, limit) in [("loop.attitude", 1_200), ("link.up.master.max", 4_500)] {
            assert!(BUDGETS.contains(&(name, limit)), "{name} ≤ {limit}");
        }
    }

    #[test]
    fn regions_are_read_from_m4counts_output() {
        let out = "region 1: 869 instructions\nregion 2: 5 instructions\nhello\ntotal 874\n";
        assert_eq!(parse_regions(out), vec![869, 5]);
    }
}
