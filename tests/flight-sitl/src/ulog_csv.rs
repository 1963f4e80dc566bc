//! A ULog file's data as CSV, one text per subscription, in the layout of pyulog's
//! `ulog2csv` (`PREFIX_NAME_MULTIID.csv`; the timestamp first, then the fields in format
//! order, arrays as `name[i]`, padding left out). Read with this project's own reader and
//! formats, so CI can hold what pyulog reads from our files against what we logged
//! (`ulog_check.py`; `flight-sitl ulog-csv FILE.ulg --out DIR`).

use std::collections::BTreeMap;

use taulink_ulog::format::{Basic, Format, Scalar};
use taulink_ulog::{Message, Reader};

/// One subscription's CSV, growing.
struct Table<'a> {
    file: String,
    format: Format<'a>,
    text: String,
}

/// The CSV of every subscription of `bytes` that has data, keyed by ulog2csv's file suffix
/// (`NAME_MULTIID.csv`).
///
/// # Errors
/// A file that does not read; data of a subscription without a format, or that does not fit
/// its format; a format with nested types (not written by this project).
pub fn tables(bytes: &[u8]) -> Result<BTreeMap<String, String>, String> {
    let mut formats: Vec<Format> = Vec::new();
    let mut subs: BTreeMap<u16, Table> = BTreeMap::new();
    for m in Reader::new(bytes).map_err(|e| e.to_string())? {
        let (offset, m) = m.map_err(|e| e.to_string())?;
        let at = |e: String| format!("offset {offset}: {e}");
        match m {
            Message::Format(f) => formats.push(f),
            Message::Subscription {
                msg_id,
                multi_id,
                name,
            } => {
                let format = formats
                    .iter()
                    .find(|f| f.name == name)
                    .cloned()
                    .ok_or_else(|| at(format!("subscription to {name} without a format")))?;
                let text = header(&format).map_err(at)?;
                let file = format!("{name}_{multi_id}.csv");
                subs.insert(msg_id, Table { file, format, text });
            }
            Message::Data { msg_id, data } => {
                let t = subs
                    .get_mut(&msg_id)
                    .ok_or_else(|| at(format!("data of unsubscribed id {msg_id}")))?;
                row(&t.format, data, &mut t.text).map_err(at)?;
            }
            _ => {}
        }
    }
    // ulog2csv writes nothing for a subscription without data.
    Ok(subs
        .into_values()
        .filter(|t| t.text.lines().nth(1).is_some())
        .map(|t| (t.file, t.text))
        .collect())
}

/// Each column: its name, basic type and offset in the message, the timestamp first.
fn columns(f: &Format) -> Result<Vec<(String, Basic, usize)>, String> {
    let mut cols = Vec::new();
    let mut offset = 0;
    for d in f.fields() {
        let basic =
            d.ty.basic
                .ok_or_else(|| format!("{}: nested type {}", f.name, d.ty.name))?;
        let size = d.ty.size().map_err(|e| e.to_string())?;
        if !d.is_padding() {
            match d.ty.array {
                Some(n) => {
                    for i in 0..usize::from(n) {
                        cols.push((format!("{}[{i}]", d.name), basic, offset + i * basic.size()));
                    }
                }
                None => cols.push((d.name.to_string(), basic, offset)),
            }
        }
        offset += size;
    }
    let at = cols
        .iter()
        .position(|c| c.0 == "timestamp")
        .ok_or_else(|| format!("{}: no timestamp", f.name))?;
    let ts = cols.remove(at);
    cols.insert(0, ts);
    Ok(cols)
}

fn header(f: &Format) -> Result<String, String> {
    let names: Vec<String> = columns(f)?.into_iter().map(|c| c.0).collect();
    Ok(names.join(",") + "\n")
}

fn row(f: &Format, data: &[u8], out: &mut String) -> Result<(), String> {
    let cells: Vec<String> = columns(f)?
        .into_iter()
        .map(|(name, basic, offset)| {
            let v = data
                .get(offset..)
                .ok_or_else(|| format!("{}: {name} past the message's end", f.name))
                .and_then(|b| {
                    Scalar::read(basic, b).map_err(|e| format!("{}: {name}: {e}", f.name))
                })?;
            Ok(match v {
                Scalar::Int(v) => v.to_string(),
                Scalar::Uint(v) => v.to_string(),
                Scalar::F32(v) => v.to_string(),
                Scalar::F64(v) => v.to_string(),
                Scalar::Bool(v) => u8::from(v).to_string(),
                Scalar::Char(v) => v.to_string(),
            })
        })
        .collect::<Result<_, String>>()?;
    out.push_str(&cells.join(","));
    out.push('\n');
    Ok(())
}
