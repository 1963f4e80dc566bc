//! The flight log's cost per profile, measured: a hover with GPS flown once per
//! `log.profile`, its log read back, and the bytes each topic takes per second over the
//! hover's last seconds (data messages whole: header, id and record). What the flight
//! README's `log-profiles` block shows (`flight-sitl log-figures --write`), so the choice
//! between profiles is made on figures, not guesses.

use flight_app::logging::{Profile, SPARKY2_LOG_AREA_BYTES, TOPICS};
use flight_app::settings::handles;
use taulink_ulog::{Message, Reader};

use crate::runner::{Kind, Options, run_kind};

/// The hover flown per profile, s.
pub const HOVER_S: f64 = 20.0;
/// The span at the log's end measured, s (the hover after the take-off).
pub const WINDOW_S: u64 = 10;

/// ULog's message header: size (2) and type (1); data messages add the id (2).
const DATA_OVERHEAD: usize = 5;
/// Logged strings: header, level (1) and timestamp (8).
const STRING_OVERHEAD: usize = 12;

/// One profile's figures: bytes per second of each topic (in `TOPICS` order), of the
/// logged strings, and the total.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileFigures {
    /// The profile.
    pub profile: Profile,
    /// Bytes per second of each topic.
    pub topics: Vec<f64>,
    /// Bytes per second of logged strings (events).
    pub strings: f64,
    /// Bytes per second of everything after the definitions.
    pub total: f64,
}

/// The figures of a log's last [`WINDOW_S`] seconds.
///
/// # Errors
/// A log that does not read.
pub fn measure(profile: Profile, bytes: &[u8]) -> Result<ProfileFigures, String> {
    let reader = Reader::new(bytes).map_err(|e| e.to_string())?;
    let mut stamped = Vec::new();
    for m in reader {
        let (_, m) = m.map_err(|e| e.to_string())?;
        match m {
            Message::Data { msg_id, data } => {
                let t = data
                    .get(..8)
                    .and_then(|b| b.try_into().ok())
                    .map(u64::from_le_bytes)
                    .ok_or("a data message without its timestamp")?;
                stamped.push((t, Some(usize::from(msg_id)), data.len() + DATA_OVERHEAD));
            }
            Message::Logging {
                timestamp_us, text, ..
            } => stamped.push((timestamp_us, None, text.len() + STRING_OVERHEAD)),
            _ => {}
        }
    }
    let end = stamped.iter().map(|s| s.0).max().unwrap_or(0);
    let from = end.saturating_sub(WINDOW_S * 1_000_000);
    let mut topics = vec![0.0; TOPICS.len()];
    let mut strings = 0.0;
    for (t, id, size) in stamped.into_iter().filter(|s| s.0 > from) {
        let per_s = size as f64 / WINDOW_S as f64;
        match id.and_then(|i| topics.get_mut(i)) {
            Some(slot) => *slot += per_s,
            None if id.is_none() => strings += per_s,
            None => return Err(format!("data of an unknown topic at {t} µs")),
        }
    }
    let total = topics.iter().sum::<f64>() + strings;
    Ok(ProfileFigures {
        profile,
        topics,
        strings,
        total,
    })
}

/// Flies the hover at `profile` and measures its log.
///
/// # Errors
/// A run that cannot be made, a log that does not read.
pub fn fly(profile: Profile) -> Result<ProfileFigures, String> {
    let mut o = Options::for_kind(Kind::Hover, true)?;
    o.duration_s = Some(HOVER_S);
    o.settings
        .put(handles::LOG_PROFILE, profile.index())
        .map_err(|e| format!("log.profile: {e}"))?;
    let outcome = run_kind(Kind::Hover, &o).map_err(|e| e.to_string())?;
    let log = outcome
        .sitl
        .flight_logs
        .first()
        .ok_or("the run wrote no log")?;
    measure(profile, log)
}

/// The Markdown table of every profile that logs: topics as rows, profiles as columns.
pub fn markdown(figures: &[ProfileFigures]) -> String {
    let mut s = String::from("| topic (B/s) |");
    let mut rule = String::from("|---|");
    for f in figures {
        s.push_str(&format!(" `{}` |", f.profile.name()));
        rule.push_str("---:|");
    }
    s.push('\n');
    s.push_str(&rule);
    s.push('\n');
    let row =
        |s: &mut String, name: &str, decimals: usize, value: &dyn Fn(&ProfileFigures) -> f64| {
            s.push_str(&format!("| {name} |"));
            for f in figures {
                let v = value(f);
                if v > 0.0 {
                    s.push_str(&format!(" {v:.decimals$} |"));
                } else {
                    s.push_str(" – |");
                }
            }
            s.push('\n');
        };
    for (i, t) in TOPICS.iter().enumerate() {
        row(&mut s, &format!("`{}`", t.name), 0, &|f| {
            f.topics.get(i).copied().unwrap_or(0.0)
        });
    }
    row(&mut s, "logged strings", 0, &|f| f.strings);
    row(&mut s, "**total**", 0, &|f| f.total);
    row(&mut s, "minutes in the Sparky2's 1 MiB log area", 1, &|f| {
        f64::from(SPARKY2_LOG_AREA_BYTES) / f.total / 60.0
    });
    s
}

/// Every profile that logs, flown and measured, as the README's table.
///
/// # Errors
/// A run or log that fails.
pub fn table() -> Result<String, String> {
    let figures = Profile::ALL
        .iter()
        .filter(|p| **p != Profile::Off)
        .map(|p| fly(*p))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(markdown(&figures))
}
