//! Video overlay frames from a flight log: `flight-sitl overlay LOG.ulg --out DIR [--fps N]`
//! draws one transparent PNG per video frame (`frame_00000.png`, …) — an attitude horizon,
//! altitude and climb rate, ground speed, the link's LQ and RSSI, the battery, the flight
//! mode and arming, the log time — for an editor to lay over the on-board video; with ffmpeg
//! on the PATH also `overlay.mov` (ProRes 4444, alpha kept). Each frame holds the latest
//! sample of every topic at its time. Text is drawn with sim-plot's embedded font.

use std::path::Path;

use flight_app::logging::{Battery, Estimate, LinkStats, SensorGps, Status, TOPICS};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use taulink_ulog::{Message, Reader, Record};
use telemetry::settings::MODES;

/// Frame size, pixels (720p).
pub const SIZE: (u32, u32) = (1280, 720);

/// What one frame shows: the latest of each topic at its time.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Frame {
    /// Log time, s.
    pub t_s: f64,
    /// The estimate.
    pub estimate: Option<Estimate>,
    /// The GPS.
    pub gps: Option<SensorGps>,
    /// The link.
    pub link: Option<LinkStats>,
    /// The battery.
    pub battery: Option<Battery>,
    /// Arming and mode.
    pub status: Option<Status>,
}

/// One decoded sample of a drawn topic.
#[derive(Debug, Clone, Copy)]
enum Sample {
    Estimate(Estimate),
    Gps(SensorGps),
    Link(LinkStats),
    Battery(Battery),
    Status(Status),
}

fn decode(name: &str, data: &[u8]) -> Result<Option<(u64, Sample)>, taulink_ulog::Error> {
    Ok(Some(match name {
        n if n == Estimate::NAME => {
            Estimate::decode(data).map(|r| (r.timestamp, Sample::Estimate(r)))?
        }
        n if n == SensorGps::NAME => {
            SensorGps::decode(data).map(|r| (r.timestamp, Sample::Gps(r)))?
        }
        n if n == LinkStats::NAME => {
            LinkStats::decode(data).map(|r| (r.timestamp, Sample::Link(r)))?
        }
        n if n == Battery::NAME => {
            Battery::decode(data).map(|r| (r.timestamp, Sample::Battery(r)))?
        }
        n if n == Status::NAME => Status::decode(data).map(|r| (r.timestamp, Sample::Status(r)))?,
        _ => return Ok(None),
    }))
}

/// The frames of a log at `fps`, from its first to its last drawn sample.
///
/// # Errors
/// A log that does not read, a record that does not decode, a rate that is not positive.
pub fn frames(bytes: &[u8], fps: f64) -> Result<Vec<Frame>, String> {
    if !(fps > 0.0 && fps <= 240.0) {
        return Err(format!("frame rate {fps}: 0 < FPS ≤ 240"));
    }
    let mut names: Vec<Option<&str>> = Vec::new();
    let mut samples = Vec::new();
    for m in Reader::new(bytes).map_err(|e| e.to_string())? {
        let (offset, m) = m.map_err(|e| e.to_string())?;
        match m {
            Message::Subscription { msg_id, name, .. } => {
                let id = usize::from(msg_id);
                if names.len() <= id {
                    names.resize(id + 1, None);
                }
                if let Some(slot) = names.get_mut(id) {
                    *slot = TOPICS.iter().find(|t| t.name == name).map(|t| t.name);
                }
            }
            Message::Data { msg_id, data } => {
                if let Some(name) = names.get(usize::from(msg_id)).copied().flatten()
                    && let Some(s) =
                        decode(name, data).map_err(|e| format!("offset {offset}: {name}: {e}"))?
                {
                    samples.push(s);
                }
            }
            _ => {}
        }
    }
    samples.sort_by_key(|s| s.0);
    let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
        return Err("no estimate, GPS, link, battery or status sample to draw".into());
    };
    let (t0, t1) = (first.0, last.0);
    let step_us = 1e6 / fps;
    let count = ((t1 - t0) as f64 / step_us).floor() as usize + 1;
    let mut out = Vec::with_capacity(count);
    let mut now = Frame::default();
    let mut next = samples.iter().peekable();
    for k in 0..count {
        let t = t0 + (k as f64 * step_us) as u64;
        while let Some((_, s)) = next.next_if(|s| s.0 <= t) {
            match *s {
                Sample::Estimate(r) => now.estimate = Some(r),
                Sample::Gps(r) => now.gps = Some(r),
                Sample::Link(r) => now.link = Some(r),
                Sample::Battery(r) => now.battery = Some(r),
                Sample::Status(r) => now.status = Some(r),
            }
        }
        now.t_s = t as f64 * 1e-6;
        out.push(now);
    }
    Ok(out)
}

/// The lines of text a frame shows, top-left and top-right.
pub fn texts(f: &Frame) -> (Vec<String>, Vec<String>) {
    let mut left = Vec::new();
    if let Some(e) = &f.estimate {
        left.push(format!("ALT {:6.1} m", e.altitude_m));
        left.push(format!("VS  {:+5.1} m/s", e.climb_mps));
    }
    if let Some(g) = &f.gps {
        left.push(format!(
            "SPD {:5.1} m/s  {} sats",
            f64::from(g.g_speed_mmps) * 1e-3,
            g.num_sv
        ));
    }
    let mut right = Vec::new();
    if let Some(s) = &f.status {
        let mode = MODES.get(usize::from(s.mode)).copied().unwrap_or("?");
        let state = if s.failsafe {
            "FAILSAFE"
        } else if s.armed {
            "ARMED"
        } else {
            "DISARMED"
        };
        right.push(format!("{state}  {}", mode.to_uppercase()));
    }
    if let Some(l) = &f.link {
        right.push(format!("LQ {:3} %  RSSI {} dBm", l.lq_percent, l.rssi_dbm));
    }
    if let Some(b) = &f.battery {
        right.push(format!(
            "BAT {:5.2} V  {:4.1} A  {} mAh",
            b.voltage_v, b.current_a, b.consumed_mah
        ));
    }
    let t = f.t_s;
    right.push(format!(
        "T {:02}:{:04.1}",
        (t / 60.0).floor() as u32,
        t % 60.0
    ));
    (left, right)
}

/// A frame as RGBA pixels (transparent where nothing is drawn).
///
/// # Errors
/// The drawing backend fails (the font cannot be registered).
pub fn draw(f: &Frame) -> Result<Vec<u8>, String> {
    sim_plot::font::register()?;
    let (w, h) = SIZE;
    // Drawn on black; black is then made transparent (text edges keep a dark rim: a shadow).
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        if let Some(est) = &f.estimate {
            horizon(&root, est.euler_deg[0], est.euler_deg[1]).map_err(e)?;
        }
        let font = (sim_plot::font::FAMILY, 30).into_font().color(&WHITE);
        let (left, right) = texts(f);
        for (i, line) in left.iter().enumerate() {
            root.draw(&Text::new(
                line.clone(),
                (30, 30 + 40 * i as i32),
                font.clone(),
            ))
            .map_err(e)?;
        }
        let anchored = font.pos(Pos::new(HPos::Right, VPos::Top));
        for (i, line) in right.iter().enumerate() {
            root.draw(&Text::new(
                line.clone(),
                (w as i32 - 30, 30 + 40 * i as i32),
                anchored.clone(),
            ))
            .map_err(e)?;
        }
        root.present().map_err(e)?;
    }
    Ok(rgb
        .as_chunks::<3>()
        .0
        .iter()
        .flat_map(|&[r, g, b]| {
            let alpha = if r | g | b == 0 { 0 } else { 255 };
            [r, g, b, alpha]
        })
        .collect())
}

/// The horizon line (rolled, moved by the pitch at 8 px/deg) and a fixed aircraft mark.
fn horizon<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    roll_deg: f32,
    pitch_deg: f32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (w, h) = SIZE;
    let (cx, cy) = (f64::from(w) / 2.0, f64::from(h) / 2.0);
    let r = f64::from(roll_deg).to_radians();
    let (dx, dy) = (r.cos() * 300.0, -r.sin() * 300.0);
    let y = cy + f64::from(pitch_deg) * 8.0;
    let p = |x: f64, y: f64| (x.round() as i32, y.round() as i32);
    let style = ShapeStyle::from(&WHITE).stroke_width(4);
    root.draw(&PathElement::new(
        vec![p(cx - dx, y - dy), p(cx + dx, y + dy)],
        style,
    ))?;
    let mark = ShapeStyle::from(&YELLOW).stroke_width(4);
    root.draw(&PathElement::new(
        vec![
            p(cx - 60.0, cy),
            p(cx - 20.0, cy),
            p(cx, cy + 15.0),
            p(cx + 20.0, cy),
            p(cx + 60.0, cy),
        ],
        mark,
    ))
}

/// Writes every frame of `bytes` into `dir` as `frame_NNNNN.png`; with ffmpeg present also
/// `overlay.mov`. Returns the frames written.
///
/// # Errors
/// A log that does not read, a file that cannot be written, ffmpeg failing.
pub fn write(bytes: &[u8], dir: &Path, fps: f64) -> Result<usize, String> {
    let frames = frames(bytes, fps)?;
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for (k, f) in frames.iter().enumerate() {
        let path = dir.join(format!("frame_{k:05}.png"));
        let file = std::fs::File::create(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), SIZE.0, SIZE.1);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        enc.write_header()
            .and_then(|mut w| w.write_image_data(&draw(f).map_err(std::io::Error::other)?))
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    let ffmpeg = std::process::Command::new("ffmpeg")
        .args([
            "-loglevel",
            "error",
            "-y",
            "-framerate",
            &fps.to_string(),
            "-i",
        ])
        .arg(dir.join("frame_%05d.png"))
        .args([
            "-c:v",
            "prores_ks",
            "-profile:v",
            "4444",
            "-pix_fmt",
            "yuva444p10le",
        ])
        .arg(dir.join("overlay.mov"))
        .status();
    match ffmpeg {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(format!("ffmpeg: {e}")),
        Ok(s) if !s.success() => return Err(format!("ffmpeg failed: {s}")),
        Ok(_) => {}
    }
    Ok(frames.len())
}
