//! The step-response figure of `lqg step --plot`, like the seed's: the response of each
//! controller with the dashed setpoint on top, the controller outputs below, time in
//! seconds; drawn by `sim-plot` (axes, units, legend, PNG or SVG).

use crate::closed_loop::StepResponse;
use sim_plot::{Figure, Panel, Series};

/// The figure for `runs` (legend name, response); `unit` is the step's ("deg/s", "deg").
/// The first run is blue, the second vermillion (sim-plot's palette order).
#[must_use]
pub fn step_figure(title: &str, unit: &str, runs: &[(&str, &StepResponse)]) -> Figure {
    #[allow(clippy::cast_precision_loss)]
    let time = |i: usize, r: &StepResponse| i as f64 * r.ts_s;
    let mut response = Panel::new("Response", format!("response ({unit})"));
    let mut output = Panel::new("Controller output", "output (±1 = full)");
    for (name, r) in runs {
        // Sample i is the state after i + 1 loop periods; output i is applied at i·Ts.
        let pts = r
            .response
            .iter()
            .enumerate()
            .map(|(i, y)| (time(i + 1, r), *y))
            .collect();
        response = response.series(Series::new(*name, pts));
        let out = r
            .output
            .iter()
            .enumerate()
            .map(|(i, u)| (time(i, r), *u))
            .collect();
        output = output.series(Series::new(*name, out).width(1));
    }
    if let Some((_, first)) = runs.first() {
        let end = time(first.response.len(), first);
        response = response.series(
            Series::new("setpoint", vec![(0.0, first.step), (end, first.step)])
                .colour(sim_plot::figure::PALETTE[6])
                .width(1)
                .dashed(),
        );
    }
    Figure::new(title)
        .panel(response)
        .panel(output.y_range(-1.05, 1.05))
}
