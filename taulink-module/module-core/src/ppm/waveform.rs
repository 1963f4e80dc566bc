//! Test waveforms: PPM edge timestamps as EdgeTX produces them (`radio/src/pulses/ppm.cpp`:
//! every channel period starts with a pulse, and a 3 ms rest period follows the last). Each
//! frame is N + 1 pulses — one starting each channel period and one starting the rest
//! period — and frames start every `frame_us`.

/// EdgeTX's default frame length for `count` channels: 22.5 ms + 2 ms per channel above 8.
pub(crate) fn edgetx_frame_us(count: usize) -> u32 {
    22_500 + 2_000 * u32::try_from(count.saturating_sub(8)).unwrap()
}

/// Edge timestamps of `frames` identical frames starting at `start_us` (wrapping).
pub(crate) fn edges(channels_us: &[u16], frame_us: u32, frames: usize, start_us: u32) -> Vec<u32> {
    let mut out = Vec::new();
    for frame in 0..frames {
        let frame_start = start_us.wrapping_add(frame_us * u32::try_from(frame).unwrap());
        let mut t = frame_start;
        out.push(t);
        for width in channels_us {
            t = t.wrapping_add(u32::from(*width));
            out.push(t);
        }
    }
    out
}
