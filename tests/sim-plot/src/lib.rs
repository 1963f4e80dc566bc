//! Shared pieces of the TauLink host tools (`taulink-sim`, `replay`, `lqg`, `sysid`, and the
//! flight-sitl scenario runner): figures made of stacked time-series panels ([`figure`]),
//! drawn with an embedded font so no system fonts are needed ([`font`]), the `--plot DIR` /
//! `--plot-format` flags every plotting tool shares ([`PlotArgs`]), and the progress bar of
//! long runs ([`progress`]), and the generated tables in the docs ([`docblock`]).
#![warn(missing_docs)]

pub mod docblock;
pub mod figure;
pub mod font;
pub mod progress;

pub use figure::{Event, Figure, Format, Panel, PlotError, Series};

use std::path::PathBuf;

/// The plot flags of every tool that draws: `--plot DIR [--plot-format png|svg]`.
#[derive(clap::Args, Clone, Debug, Default, PartialEq, Eq)]
pub struct PlotArgs {
    /// Write the figures into this directory (created if needed).
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Image format of the figures: png (1000 px wide bitmaps) or svg (vector, for papers
    /// and browsers).
    #[arg(long, value_enum, default_value_t = Format::Png, requires = "plot")]
    pub plot_format: Format,
}

impl PlotArgs {
    /// Path of the figure `stem` (e.g. `"attitude"`) in the plot directory, with the
    /// format's extension; `None` without `--plot`.
    #[must_use]
    pub fn path(&self, stem: &str) -> Option<PathBuf> {
        self.plot
            .as_ref()
            .map(|dir| dir.join(format!("{stem}.{}", self.plot_format.extension())))
    }
}
