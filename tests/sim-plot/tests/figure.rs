//! Draws a two-panel figure in both formats and checks what a reader needs is in the file:
//! the SVG (text) carries the titles, axis labels, legend names and event labels; the PNG
//! has text pixels (the embedded font drew something) in the label areas.

use sim_plot::{Event, Figure, Format, Panel, Series};

fn figure() -> Figure {
    let sine: Vec<(f64, f64)> = (0..2000)
        .map(|i| {
            let t = f64::from(i) * 0.005;
            (t, (t * 3.0).sin() * 20.0)
        })
        .collect();
    let truth: Vec<(f64, f64)> = sine.iter().map(|&(t, y)| (t, y * 0.9)).collect();
    Figure::new("Test figure")
        .panel(
            Panel::new("Roll", "roll (deg)")
                .series(Series::new("estimate", sine.clone()))
                .series(Series::new("truth", truth))
                .event(Event::new(4.0, "link cut")),
        )
        .panel(Panel::new("Motor", "command (0–1)").series(Series::new(
            "motor 1",
            sine.iter().map(|&(t, y)| (t, y / 40.0 + 0.5)).collect(),
        )))
}

#[test]
fn svg_carries_every_label() {
    let dir = std::env::temp_dir().join(format!("sim-plot-test-{}", std::process::id()));
    let path = dir.join("fig.svg");
    figure().save(&path).unwrap();
    let svg = std::fs::read_to_string(&path).unwrap();
    for text in [
        "Test figure",
        "Roll",
        "roll (deg)",
        "estimate",
        "truth",
        "link cut",
        "time (s)",
        "motor 1",
    ] {
        assert!(svg.contains(text), "{text} missing from the SVG");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn png_is_written() {
    let dir = std::env::temp_dir().join(format!("sim-plot-png-{}", std::process::id()));
    let path = dir.join("fig.png");
    figure().save_as(&path, Format::Png).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bitmap_has_glyphs_in_the_title_and_y_label_strips() {
    let (rgb, (w, h)) = figure().render_rgb().unwrap();
    let (w, h) = (w as usize, h as usize);
    let dark = |x0: usize, x1: usize, y0: usize, y1: usize| {
        (y0..y1)
            .flat_map(|y| (x0..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| rgb[(y * w + x) * 3] < 200)
            .count()
    };
    // The 36 px title row is white without text; with the embedded font it has glyphs.
    assert!(dark(0, w, 0, 36) > 100, "no title text");
    // The y tick labels and the rotated y label live in the left 78 px of each panel.
    assert!(dark(0, 70, 40, h / 2) > 100, "no y-axis text in panel 1");
    assert!(
        dark(0, 70, h / 2, h - 30) > 100,
        "no y-axis text in panel 2"
    );
}
