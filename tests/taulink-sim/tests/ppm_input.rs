//! The PPM handset as the module firmware takes it: an edge train through the module's own
//! decoder, each frame handed to the link when the firmware's capture task releases it.

use taulink_handset::crsf::channels::us_to_ticks;
use taulink_sim::handset::{Handset, HandsetFrame, HandsetKind};
use taulink_sim::ppm_input::{PPM_CHANNELS, stamp, widths_us};
use telemetry::channels::CHANNEL_CENTER;

const SALT: u64 = 7;

/// Every distinct frame the module's input handed over in the first `duration_us`, polled
/// every 10 µs (finer than anything the link does).
fn frames(duration_us: u64) -> (Vec<HandsetFrame>, Handset) {
    let mut handset = Handset::new(HandsetKind::Ppm, SALT);
    let mut seen: Vec<HandsetFrame> = Vec::new();
    for t in (0..duration_us).step_by(10) {
        if let Some(f) = handset.advance(t, |_| {})
            && seen.last() != Some(&f)
        {
            seen.push(f);
        }
    }
    (seen, handset)
}

#[test]
fn a_ppm_frame_reaches_the_link_at_its_last_edge_unless_it_jumped() {
    let (seen, handset) = frames(10_000_000);
    // 10 s of 22.5 ms frames: the decoder finds sync on the first, acquires on the next
    // five and hands out the sixth (k = 5) at the next frame's first edge; every later
    // frame goes out, each one.
    let first = seen.first().unwrap();
    assert_eq!(first.k, 5);
    assert!(first.arrived_us - first.generated_us > 6_000, "{first:?}");
    for pair in seen.windows(2) {
        assert_eq!(pair[1].k, pair[0].k + 1);
    }
    let (mut early, mut held) = (0, 0);
    for pair in seen.windows(2) {
        let (before, f) = (widths_us(SALT, pair[0].k), widths_us(SALT, pair[1].k));
        // The decoder's factory rule: every channel within 200 µs of the frame before
        // (±2 µs of capture), else the sync-gap proof.
        let jumped = before.iter().zip(&f).any(|(a, b)| a.abs_diff(*b) > 198);
        let hold = pair[1].arrived_us - pair[1].generated_us;
        if jumped {
            // `release_deadline_us` (2 501 µs after the last channel's edge), on the
            // firmware's next 32 768 Hz timer tick (≤ 30.5 µs later).
            assert!((2_501..=2_532).contains(&hold), "{:?}", pair[1]);
            held += 1;
        } else {
            assert_eq!(hold, 0, "{:?}", pair[1]);
            early += 1;
        }
    }
    // The pilot flips a switch every 4 s or so, and nothing else jumps.
    assert!((1..=4).contains(&held), "{held} held, {early} early");
    assert_eq!(handset.ppm_released(), (early + held + 1, early));
}

#[test]
fn the_pilot_moves_the_sticks_smoothly_and_the_stamp_names_every_frame() {
    let mut moved = [0u16; PPM_CHANNELS];
    let mut last = widths_us(SALT, 0);
    for k in 1..200_000u64 {
        let w = widths_us(SALT, k);
        for (i, (a, b)) in last.iter().zip(&w).enumerate() {
            assert!(
                (988..=2_012).contains(b),
                "channel {} at frame {k}: {b}",
                i + 1
            );
            if i < 4 {
                // The stamp channels move ≤ 4 µs a frame, the smooth stick ≤ 41 µs.
                assert!(a.abs_diff(*b) <= if i < 3 { 4 } else { 41 }, "{k}: {w:?}");
            }
            moved[i] = moved[i].max(a.abs_diff(*b));
        }
        let channels: Vec<u16> = w.iter().map(|us| us_to_ticks(*us)).collect();
        let mut all = [CHANNEL_CENTER; 16];
        all[..PPM_CHANNELS].copy_from_slice(&channels);
        assert_eq!(stamp(&all), k);
        last = w;
    }
    // The switches really flip (by a whole step at least).
    assert!(moved[4..].iter().all(|m| *m >= 512), "{moved:?}");
}

#[test]
fn the_link_gets_what_the_decoder_made_of_the_edges() {
    let (seen, handset) = frames(1_000_000);
    assert_eq!(handset.rejected(), 0);
    for f in &seen {
        assert_eq!(stamp(&f.channels), f.k);
        // Each period is captured to the µs (±1 µs: 1.6 ticks).
        for (got, sent) in f.channels.iter().zip(widths_us(SALT, f.k)) {
            assert!(got.abs_diff(us_to_ticks(sent)) <= 2, "{f:?}");
        }
        // The rest of the 16 are centred, as `AirLink` fills them.
        assert!(
            f.channels[PPM_CHANNELS..]
                .iter()
                .all(|c| *c == CHANNEL_CENTER)
        );
    }
}
