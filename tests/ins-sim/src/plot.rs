//! PNG plots of a replay (plotters, bitmap backend, no fonts): `attitude.png` (roll, pitch,
//! yaw in degrees), `velocity.png`, `position.png` (N, E, D) and `bias.png` (gyro x, y, z and
//! accel z), one panel per component, time on x. Estimate in blue, reference in red.

use std::path::Path;

use plotters::prelude::*;

use crate::replay::Row;
use crate::trajectory::to_euler;

type Series = Vec<(f64, f64)>;

fn series(rows: &[Row], f: impl Fn(&Row) -> f64) -> Series {
    rows.iter()
        .map(|r| (r.time_us as f64 * 1e-6, f(r)))
        .collect()
}

fn panel_range(all: &[&Series]) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
    let (mut t0, mut t1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for s in all {
        for &(t, y) in s.iter() {
            t0 = t0.min(t);
            t1 = t1.max(t);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    if t0 > t1 {
        return (0.0..1.0, -1.0..1.0);
    }
    let pad = ((y1 - y0) * 0.05).max(1e-3);
    (t0..t1.max(t0 + 1e-3), (y0 - pad)..(y1 + pad))
}

fn draw(
    path: &Path,
    panels: &[(Series, Option<Series>)],
) -> Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::new(path, (1000, 250 * panels.len() as u32)).into_drawing_area();
    root.fill(&WHITE)?;
    for (area, (est, reference)) in root.split_evenly((panels.len(), 1)).iter().zip(panels) {
        let mut all = vec![est];
        if let Some(r) = reference {
            all.push(r);
        }
        let (x, y) = panel_range(&all);
        let mut chart = ChartBuilder::on(area).margin(8).build_cartesian_2d(x, y)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .y_labels(5)
            .x_labels(10)
            .draw()?;
        if let Some(r) = reference {
            chart.draw_series(LineSeries::new(r.iter().copied(), &RED))?;
        }
        chart.draw_series(LineSeries::new(est.iter().copied(), &BLUE))?;
    }
    root.present()?;
    Ok(())
}

/// Writes the four PNGs into `dir` (created if needed).
///
/// # Errors
/// File-system or drawing errors.
pub fn write_plots(
    dir: &Path,
    estimates: &[Row],
    reference: Option<&[Row]>,
) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let euler = |i: usize| {
        move |r: &Row| {
            to_euler(r.attitude)
                .get(i)
                .copied()
                .unwrap_or(0.0)
                .to_degrees()
        }
    };
    let both = |f: &dyn Fn(&Row) -> f64| (series(estimates, f), reference.map(|r| series(r, f)));
    let attitude: Vec<_> = (0..3).map(|i| both(&euler(i))).collect();
    draw(&dir.join("attitude.png"), &attitude)?;
    let velocity: Vec<_> = (0..3)
        .map(|i| both(&move |r: &Row| r.velocity_ned_mps.get(i).copied().unwrap_or(0.0)))
        .collect();
    draw(&dir.join("velocity.png"), &velocity)?;
    let position: Vec<_> = (0..3)
        .map(|i| both(&move |r: &Row| r.position_ned_m.get(i).copied().unwrap_or(0.0)))
        .collect();
    draw(&dir.join("position.png"), &position)?;
    let mut bias: Vec<_> = (0..3)
        .map(|i| {
            (
                series(estimates, move |r: &Row| {
                    r.gyro_bias_radps.get(i).copied().unwrap_or(0.0)
                }),
                None,
            )
        })
        .collect();
    bias.push((series(estimates, |r: &Row| r.accel_bias_z_mps2), None));
    draw(&dir.join("bias.png"), &bias)?;
    Ok(())
}
