//! The `magcal` tool's logic: read a magnetometer log (`time_us,mx,my,mz`), fit and check a
//! hard/soft-iron calibration with `flight_app::estimation::magcal`, and print it as text
//! or JSON.

use flight_app::estimation::magcal::{MagCalConfig, MagCalibration, fit};

/// The CSV header the tool expects.
pub const HEADER: &str = "time_us,mx,my,mz";

/// Reads the samples of a `time_us,mx,my,mz` CSV (any consistent field unit).
///
/// # Errors
/// A missing or different header, or a malformed line (named by number).
pub fn parse_csv(text: &str) -> Result<Vec<[f32; 3]>, String> {
    let mut lines = text.lines().enumerate();
    let header = lines
        .by_ref()
        .find(|(_, l)| !l.trim().is_empty())
        .map(|(_, l)| l.trim().replace(' ', ""));
    if header.as_deref() != Some(HEADER) {
        return Err(format!("expected the header {HEADER:?}"));
    }
    let mut out = Vec::new();
    for (i, line) in lines {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let [t, x, y, z] = fields.as_slice() else {
            return Err(format!("line {}: expected 4 values", i + 1));
        };
        t.parse::<u64>()
            .map_err(|_| format!("line {}: bad time {t:?}", i + 1))?;
        let mut v = [0f32; 3];
        for (o, f) in v.iter_mut().zip([x, y, z]) {
            *o = f
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("line {}: not a finite number: {f:?}", i + 1))?;
        }
        out.push(v);
    }
    Ok(out)
}

/// Fits and checks; the error is the reason the data cannot determine a calibration.
///
/// # Errors
/// The refused check, in words.
pub fn calibrate(samples: &[[f32; 3]]) -> Result<MagCalibration, String> {
    fit(samples, &MagCalConfig::default()).map_err(|e| e.to_string())
}

/// Human-readable result.
#[must_use]
pub fn to_text(c: &MagCalibration, samples: usize) -> String {
    let [o0, o1, o2] = c.offset;
    let mut s = format!("samples       {samples}\noffset        {o0:.6} {o1:.6} {o2:.6}\n");
    for (i, [a, b, d]) in c.matrix.iter().enumerate() {
        let label = if i == 0 { "matrix" } else { "" };
        s.push_str(&format!("{label:<14}{a:.6} {b:.6} {d:.6}\n"));
    }
    s.push_str(&format!(
        "field         {:.6}\nresidual_pct  {:.3}\ncoverage      {:.3}\n",
        c.field, c.residual_pct, c.coverage
    ));
    s
}

/// One JSON object: `offset`, `matrix` (rows), `field`, `residual_pct`, `coverage`,
/// `samples`.
#[must_use]
pub fn to_json(c: &MagCalibration, samples: usize) -> String {
    let row = |r: &[f32; 3]| format!("[{},{},{}]", r[0], r[1], r[2]);
    let rows: Vec<String> = c.matrix.iter().map(row).collect();
    format!(
        "{{\"offset\":{},\"matrix\":[{}],\"field\":{},\"residual_pct\":{},\"coverage\":{},\"samples\":{samples}}}",
        row(&c.offset),
        rows.join(","),
        c.field,
        c.residual_pct,
        c.coverage
    )
}
