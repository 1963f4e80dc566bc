//! Figures of a replay, drawn by `sim-plot` (axes, units, legends, PNG or SVG):
//! `attitude` (roll, pitch, yaw in degrees), `velocity` and `position` (N, E, D) and `bias`
//! (gyro x, y, z in deg/s, accel z in m/s²), one panel per component, time in seconds.
//! Estimate blue, reference (the `--truth` file) vermillion.

use std::path::Path;

use sim_plot::{Figure, Format, Panel, PlotError, Series};

use crate::replay::Row;
use crate::trajectory::to_euler;

fn series(rows: &[Row], f: &dyn Fn(&Row) -> f64) -> Vec<(f64, f64)> {
    rows.iter()
        .map(|r| (r.time_us as f64 * 1e-6, f(r)))
        .collect()
}

/// A panel of the estimate and, if given, the reference.
fn panel(
    title: &str,
    y_label: &str,
    estimates: &[Row],
    reference: Option<&[Row]>,
    f: &dyn Fn(&Row) -> f64,
) -> Panel {
    let p = Panel::new(title, y_label).series(Series::new("estimate", series(estimates, f)));
    match reference {
        Some(r) => p.series(Series::new("reference", series(r, f)).width(1)),
        None => p,
    }
}

/// Writes `attitude`, `velocity`, `position` and `bias` in `format` into `dir` (created if
/// needed); returns the paths written.
///
/// # Errors
/// File-system or drawing errors.
pub fn write_plots(
    dir: &Path,
    format: Format,
    estimates: &[Row],
    reference: Option<&[Row]>,
) -> Result<Vec<std::path::PathBuf>, PlotError> {
    let euler = |i: usize| {
        move |r: &Row| {
            to_euler(r.attitude)
                .get(i)
                .copied()
                .unwrap_or(0.0)
                .to_degrees()
        }
    };
    let pick = |v: [f64; 3], i: usize| v.get(i).copied().unwrap_or(0.0);
    let axes = ["north", "east", "down"];
    let mut attitude = Figure::new("Attitude: estimate vs reference");
    for (i, name) in ["roll", "pitch", "yaw"].into_iter().enumerate() {
        let label = format!("{name} (deg)");
        attitude = attitude.panel(panel(name, &label, estimates, reference, &euler(i)));
    }
    let mut velocity = Figure::new("Velocity (NED)");
    let mut position = Figure::new("Position (NED, from the first GPS fix)");
    for (i, name) in axes.into_iter().enumerate() {
        let v = move |r: &Row| pick(r.velocity_ned_mps, i);
        let p = move |r: &Row| pick(r.position_ned_m, i);
        velocity = velocity.panel(panel(
            name,
            &format!("v {name} (m/s)"),
            estimates,
            reference,
            &v,
        ));
        position = position.panel(panel(
            name,
            &format!("{name} (m)"),
            estimates,
            reference,
            &p,
        ));
    }
    let mut bias = Figure::new("Estimated sensor biases");
    for (i, name) in ["gyro x", "gyro y", "gyro z"].into_iter().enumerate() {
        let b = move |r: &Row| pick(r.gyro_bias_radps, i).to_degrees();
        bias = bias.panel(panel(name, &format!("{name} (deg/s)"), estimates, None, &b));
    }
    bias = bias.panel(panel(
        "accel z",
        "accel z (m/s²)",
        estimates,
        None,
        &|r: &Row| r.accel_bias_z_mps2,
    ));
    let mut written = Vec::new();
    for (name, fig) in [
        ("attitude", attitude),
        ("velocity", velocity),
        ("position", position),
        ("bias", bias),
    ] {
        let path = dir.join(format!("{name}.{}", format.extension()));
        fig.save_as(&path, format)?;
        written.push(path);
    }
    Ok(written)
}
