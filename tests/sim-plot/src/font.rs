//! The embedded font: a subset of DejaVu Sans (Latin-1, Greek, arrows, math signs;
//! `fonts/LICENSE-DejaVu.txt`) registered with plotters' `ab_glyph` text renderer under the
//! family names the figures use. Bundling it means a PNG has axis labels on any machine,
//! with no fontconfig or system fonts (CI containers have none).

use std::sync::OnceLock;

use plotters::style::{FontStyle, register_font};

/// The font file (30 KB).
pub const DEJAVU_SANS: &[u8] = include_bytes!("../fonts/DejaVuSans-subset.ttf");

/// The family name figures ask for.
pub const FAMILY: &str = "sans-serif";

/// Registers the font once per process; later calls return the first result.
///
/// # Errors
/// The bundled file is not a font plotters can read (it is, the tests draw with it).
pub fn register() -> Result<(), &'static str> {
    static DONE: OnceLock<Result<(), &'static str>> = OnceLock::new();
    *DONE.get_or_init(|| {
        // Other styles (bold captions) fall back to this one.
        register_font(FAMILY, FontStyle::Normal, DEJAVU_SANS)
            .map_err(|_| "the bundled DejaVu Sans subset is not a readable font")
    })
}
