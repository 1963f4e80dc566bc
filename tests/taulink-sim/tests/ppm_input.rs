//! The PPM handset as the module firmware takes it: an edge train through the module's own
//! decoder, each frame handed to the link when the firmware's capture task releases it.

use taulink_sim::handset::{Handset, HandsetFrame, HandsetKind};
use taulink_sim::ppm_input::{PPM_CHANNELS, stamp, widths_us};
use telemetry::channels::CHANNEL_CENTER;
use telemetry::handset::crsf::channels::us_to_ticks;

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
fn a_locked_ppm_frame_reaches_the_link_a_sync_gap_after_its_last_channel() {
    let (seen, _) = frames(1_000_000);
    // 1 s of 22.5 ms frames: the decoder finds sync on the first, acquires on the next
    // five and hands out the sixth (k = 5) at the next frame's first edge; every later
    // frame goes out early, each one.
    assert!(seen.len() >= 38, "{}", seen.len());
    let first = seen.first().unwrap();
    assert_eq!(first.k, 5);
    assert!(first.arrived_us - first.generated_us > 6_000, "{first:?}");
    for pair in seen.windows(2) {
        assert_eq!(pair[1].k, pair[0].k + 1);
    }
    for f in &seen[1..] {
        // `release_deadline_us` (2 501 µs after the last channel's edge), on the firmware's
        // next 32 768 Hz timer tick (≤ 30.5 µs later).
        let hold = f.arrived_us - f.generated_us;
        assert!((2_501..=2_532).contains(&hold), "{f:?}");
    }
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
