//! A figure of stacked time-series panels sharing one time axis: each panel has a title, a
//! y-axis label with its unit, named series (legend, colour, optional dashing) and optional
//! event markers (a labelled vertical line: "link cut", "step", "failsafe"). Saved as PNG or
//! SVG by [`Figure::save`].
//!
//! Colours come from the Okabe–Ito palette, which stays distinguishable for colour-blind
//! readers and in greyscale print: the first series of a panel (by convention the estimate
//! or the response) is blue, the second (truth, reference, setpoint) vermillion.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::font;

/// Series colours in order (Okabe–Ito): blue, vermillion, bluish green, reddish purple,
/// orange, sky blue, black.
pub const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
];

/// Most points drawn per series: longer series are reduced to the minimum and maximum of
/// each bucket, so the envelope (spikes included) survives and an SVG stays small.
pub const MAX_POINTS: usize = 4000;

/// Output format.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Bitmap.
    #[default]
    Png,
    /// Vector.
    Svg,
}

impl Format {
    /// The file extension.
    #[must_use]
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Svg => "svg",
        }
    }

    /// The format a path's extension names (`.svg` → SVG, anything else PNG).
    #[must_use]
    pub fn of_path(path: &Path) -> Self {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("svg") => Format::Svg,
            _ => Format::Png,
        }
    }
}

/// Why a figure could not be written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlotError(pub String);

impl std::fmt::Display for PlotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PlotError {}

fn err(e: impl std::fmt::Display) -> PlotError {
    PlotError(e.to_string())
}

/// One named curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// (time, value) points; non-finite values are left out.
    pub points: Vec<(f64, f64)>,
    /// Colour; `None` takes the panel's next palette colour.
    pub colour: Option<RGBColor>,
    /// Drawn dashed (setpoints, limits).
    pub dashed: bool,
    /// Line width, pixels.
    pub width: u32,
}

impl Series {
    /// A solid 2 px series in the next palette colour.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            colour: None,
            dashed: false,
            width: 2,
        }
    }

    /// Dashed.
    #[must_use]
    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }

    /// A fixed colour.
    #[must_use]
    pub fn colour(mut self, c: RGBColor) -> Self {
        self.colour = Some(c);
        self
    }

    /// Line width in pixels.
    #[must_use]
    pub fn width(mut self, w: u32) -> Self {
        self.width = w;
        self
    }
}

/// A labelled instant drawn as a dashed grey vertical line across a panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    /// Time, in the figure's x unit.
    pub t: f64,
    /// Label written next to the line's top.
    pub label: String,
}

impl Event {
    /// An event at `t`.
    pub fn new(t: f64, label: impl Into<String>) -> Self {
        Self {
            t,
            label: label.into(),
        }
    }
}

/// One panel: title, y label (say the unit: "roll (deg)"), series, events.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Panel {
    /// Title above the panel.
    pub title: String,
    /// Y-axis label with its unit.
    pub y_label: String,
    /// The curves.
    pub series: Vec<Series>,
    /// Event markers.
    pub events: Vec<Event>,
    /// Fixed y range; `None` fits the data (5 % margin).
    pub y_range: Option<(f64, f64)>,
}

impl Panel {
    /// An empty panel.
    pub fn new(title: impl Into<String>, y_label: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            y_label: y_label.into(),
            ..Self::default()
        }
    }

    /// Adds a series.
    #[must_use]
    pub fn series(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }

    /// Adds an event marker.
    #[must_use]
    pub fn event(mut self, e: Event) -> Self {
        self.events.push(e);
        self
    }

    /// Fixes the y range.
    #[must_use]
    pub fn y_range(mut self, lo: f64, hi: f64) -> Self {
        self.y_range = Some((lo, hi));
        self
    }
}

/// Stacked panels over one x axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// Title over the whole figure.
    pub title: String,
    /// X-axis label with its unit (written under the bottom panel).
    pub x_label: String,
    /// Panels, top to bottom.
    pub panels: Vec<Panel>,
    /// Width in pixels.
    pub width: u32,
    /// Height of one panel in pixels.
    pub panel_height: u32,
}

impl Figure {
    /// A 1000 px wide figure with 260 px panels and time in seconds on x.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            x_label: "time (s)".into(),
            panels: Vec::new(),
            width: 1000,
            panel_height: 260,
        }
    }

    /// Sets the x label.
    #[must_use]
    pub fn x_label(mut self, l: impl Into<String>) -> Self {
        self.x_label = l.into();
        self
    }

    /// Adds a panel.
    #[must_use]
    pub fn panel(mut self, p: Panel) -> Self {
        self.panels.push(p);
        self
    }

    fn height(&self) -> u32 {
        let n = u32::try_from(self.panels.len()).unwrap_or(u32::MAX).max(1);
        TITLE_PX + n.saturating_mul(self.panel_height) + X_LABEL_PX
    }

    /// Writes the figure to `path`, PNG or SVG by the path's extension.
    ///
    /// # Errors
    /// File-system or drawing errors, or a font that cannot be registered.
    pub fn save(&self, path: &Path) -> Result<(), PlotError> {
        self.save_as(path, Format::of_path(path))
    }

    /// Writes the figure to `path` in `format`.
    ///
    /// # Errors
    /// As [`Figure::save`].
    pub fn save_as(&self, path: &Path, format: Format) -> Result<(), PlotError> {
        font::register().map_err(err)?;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| err(format!("{}: {e}", dir.display())))?;
        }
        let size = (self.width, self.height());
        match format {
            Format::Png => {
                let root = BitMapBackend::new(path, size).into_drawing_area();
                self.draw(&root)?;
                root.present().map_err(err)
            }
            Format::Svg => {
                let root = SVGBackend::new(path, size).into_drawing_area();
                self.draw(&root)?;
                root.present().map_err(err)
            }
        }
    }

    /// Draws into an RGB buffer (3 bytes a pixel, row-major, `width × height`), for tests
    /// and for callers that encode images themselves. Returns the buffer and its size.
    ///
    /// # Errors
    /// As [`Figure::save`].
    pub fn render_rgb(&self) -> Result<(Vec<u8>, (u32, u32)), PlotError> {
        font::register().map_err(err)?;
        let size = (self.width, self.height());
        let len = usize::try_from(u64::from(size.0) * u64::from(size.1) * 3).map_err(err)?;
        let mut buf = vec![0u8; len];
        {
            let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(err)?;
        }
        Ok((buf, size))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), PlotError> {
        root.fill(&WHITE).map_err(err)?;
        let (title, rest) = root.split_vertically(TITLE_PX);
        title
            .titled(
                &self.title,
                (font::FAMILY, 22).into_font().style(FontStyle::Bold),
            )
            .map_err(err)?;
        let (t0, t1) = self.x_range();
        let n = self.panels.len().max(1);
        let areas = rest.split_evenly((n, 1));
        let last = self.panels.len().saturating_sub(1);
        for (i, (area, panel)) in areas.iter().zip(&self.panels).enumerate() {
            let x_label = (i == last).then_some(self.x_label.as_str());
            draw_panel(area, panel, (t0, t1), x_label)?;
        }
        Ok(())
    }

    fn x_range(&self) -> (f64, f64) {
        let xs = self
            .panels
            .iter()
            .flat_map(|p| p.series.iter())
            .flat_map(|s| s.points.iter())
            .map(|p| p.0);
        let (lo, hi) = bounds(xs);
        if lo < hi { (lo, hi) } else { (lo, lo + 1.0) }
    }
}

const TITLE_PX: u32 = 36;
const X_LABEL_PX: u32 = 24;

/// Min and max of the finite values; (0, 0) if none.
fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo <= hi { (lo, hi) } else { (0.0, 0.0) }
}

fn y_range(panel: &Panel) -> (f64, f64) {
    if let Some(r) = panel.y_range {
        return r;
    }
    let (lo, hi) = bounds(
        panel
            .series
            .iter()
            .flat_map(|s| s.points.iter())
            .map(|p| p.1),
    );
    let pad = ((hi - lo) * 0.05)
        .max(hi.abs().max(lo.abs()) * 1e-3)
        .max(1e-9);
    (lo - pad, hi + pad)
}

/// Keeps at most [`MAX_POINTS`]: the min and max (in time order) of equal buckets.
#[must_use]
pub fn decimate(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let finite = points
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    if points.len() <= MAX_POINTS {
        return finite.collect();
    }
    let per = points.len().div_ceil(MAX_POINTS / 2);
    let mut out = Vec::with_capacity(MAX_POINTS + 2);
    for chunk in points.chunks(per) {
        let ok = chunk.iter().filter(|p| p.0.is_finite() && p.1.is_finite());
        let lo = ok.clone().min_by(|a, b| a.1.total_cmp(&b.1));
        let hi = ok.max_by(|a, b| a.1.total_cmp(&b.1));
        match (lo, hi) {
            (Some(&a), Some(&b)) if a.0 <= b.0 => out.extend([a, b]),
            (Some(&a), Some(&b)) => out.extend([b, a]),
            _ => {}
        }
    }
    out.dedup();
    out
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    (t0, t1): (f64, f64),
    x_label: Option<&str>,
) -> Result<(), PlotError> {
    let (y0, y1) = y_range(panel);
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (font::FAMILY, 16))
        .margin_left(10)
        .margin_right(20)
        .margin_top(4)
        .x_label_area_size(if x_label.is_some() { 44 } else { 24 })
        .y_label_area_size(78)
        .build_cartesian_2d(t0..t1, y0..y1)
        .map_err(err)?;
    let y_tick = |v: &f64| tick(*v, y1 - y0);
    let x_tick = |v: &f64| tick(*v, t1 - t0);
    let mut mesh = chart.configure_mesh();
    mesh.light_line_style(RGBColor(246, 246, 246))
        .bold_line_style(RGBColor(205, 205, 205))
        .x_labels(12)
        .y_labels(6)
        .label_style((font::FAMILY, 13))
        .axis_desc_style((font::FAMILY, 14))
        .y_desc(panel.y_label.as_str())
        .y_label_formatter(&y_tick);
    if let Some(x) = x_label {
        mesh.x_desc(x);
    }
    mesh.x_label_formatter(&x_tick).draw().map_err(err)?;

    for (k, e) in panel.events.iter().enumerate() {
        let grey = RGBColor(110, 110, 110);
        chart
            .draw_series(DashedLineSeries::new(
                [(e.t, y0), (e.t, y1)],
                5,
                4,
                grey.stroke_width(1),
            ))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(
                EmptyElement::at((e.t, y1))
                    + Text::new(
                        e.label.clone(),
                        // Close events (a cut and the failsafe it causes) would print
                        // over each other: step the labels down in turn.
                        (4, 3 + 14 * (k % 4) as i32),
                        (font::FAMILY, 12).into_font().color(&grey),
                    ),
            ))
            .map_err(err)?;
    }

    let mut palette = PALETTE.iter().cycle();
    let mut labelled = false;
    for s in &panel.series {
        let colour = s
            .colour
            .or_else(|| palette.next().copied())
            .unwrap_or(BLACK);
        let style = colour.stroke_width(s.width);
        let points = decimate(&s.points);
        let anno = if s.dashed {
            chart
                .draw_series(DashedLineSeries::new(points, 8, 5, style))
                .map_err(err)?
        } else {
            chart
                .draw_series(LineSeries::new(points, style))
                .map_err(err)?
        };
        if !s.name.is_empty() {
            labelled = true;
            anno.label(s.name.as_str()).legend(move |(x, y)| {
                PathElement::new([(x, y), (x + 22, y)], colour.stroke_width(3))
            });
        }
    }
    if labelled {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .label_font((font::FAMILY, 13))
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

/// Tick label: few significant digits, no float noise ("0.30000000000000004", or
/// "-1.4e-17" for a zero tick on an axis spanning `span`).
fn tick(v: f64, span: f64) -> String {
    let a = v.abs();
    if a <= span.abs() * 1e-9 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.1e}")
    } else {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" { "0".into() } else { s.into() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_the_envelope_and_the_bound() {
        let mut pts: Vec<(f64, f64)> = (0..100_000).map(|i| (f64::from(i), 0.0)).collect();
        pts[54_321].1 = 7.0;
        pts[77_777].1 = -3.0;
        pts[100].1 = f64::NAN;
        let d = decimate(&pts);
        assert!(d.len() <= MAX_POINTS);
        assert!(d.contains(&(54_321.0, 7.0)));
        assert!(d.contains(&(77_777.0, -3.0)));
        assert!(d.iter().all(|p| p.1.is_finite()));
        assert!(d.windows(2).all(|w| w[0].0 <= w[1].0));
    }

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(0.30000000000000004, 1.0), "0.3");
        assert_eq!(tick(-0.00001, 1e-4), "-1.0e-5");
        assert_eq!(tick(250.0, 1000.0), "250");
        assert_eq!(tick(0.0, 1.0), "0");
        assert_eq!(tick(-1.4e-17, 0.2), "0");
    }

    #[test]
    fn format_from_extension() {
        assert_eq!(Format::of_path(Path::new("a/b.SVG")), Format::Svg);
        assert_eq!(Format::of_path(Path::new("a/b.png")), Format::Png);
        assert_eq!(Format::of_path(Path::new("a/b")), Format::Png);
    }
}
