//! Step-response figures like the seed's: response and setpoint on top, controller output
//! below, drawn with plotters' bitmap backend. No text: the bitmap backend needs a font
//! library this build leaves out, so the axes carry no labels (the JSON has the numbers).

use crate::closed_loop::StepResponse;
use plotters::prelude::*;

/// Draws `runs` (name, response) into a PNG at `path`: panel 1 response + dashed setpoint,
/// panel 2 output. Colours: first run blue, second red, further ones green/magenta.
pub fn step_png(
    path: &str,
    runs: &[(&str, &StepResponse)],
) -> Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(400);
    let colours = [BLUE, RED, GREEN, MAGENTA];
    let Some((_, first)) = runs.first() else {
        return Ok(());
    };
    #[allow(clippy::cast_precision_loss)]
    let t_end = first.response.len() as f64 * first.ts_s;
    let y_max = runs
        .iter()
        .flat_map(|(_, r)| r.response.iter())
        .fold(first.step, |m, v| m.max(*v))
        * 1.1;
    let y_min = runs
        .iter()
        .flat_map(|(_, r)| r.response.iter())
        .fold(0.0f64, |m, v| m.min(*v));
    let mut chart = ChartBuilder::on(&top)
        .margin(15)
        .build_cartesian_2d(0.0..t_end, y_min..y_max)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_labels(0)
        .draw()?;
    chart.draw_series(DashedLineSeries::new(
        vec![(0.0, first.step), (t_end, first.step)],
        6,
        4,
        BLACK.into(),
    ))?;
    for ((_, r), c) in runs.iter().zip(colours.iter().cycle()) {
        #[allow(clippy::cast_precision_loss)]
        let pts = r
            .response
            .iter()
            .enumerate()
            .map(|(i, y)| ((i + 1) as f64 * r.ts_s, *y));
        chart.draw_series(LineSeries::new(pts, c.stroke_width(2)))?;
    }
    let mut out = ChartBuilder::on(&bottom)
        .margin(15)
        .build_cartesian_2d(0.0..t_end, -1.05f64..1.05)?;
    out.configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_labels(0)
        .draw()?;
    out.draw_series(LineSeries::new(vec![(0.0, 0.0), (t_end, 0.0)], BLACK))?;
    for ((_, r), c) in runs.iter().zip(colours.iter().cycle()) {
        #[allow(clippy::cast_precision_loss)]
        let pts = r
            .output
            .iter()
            .enumerate()
            .map(|(i, y)| (i as f64 * r.ts_s, *y));
        out.draw_series(LineSeries::new(pts, c.stroke_width(1)))?;
    }
    root.present()?;
    Ok(())
}
