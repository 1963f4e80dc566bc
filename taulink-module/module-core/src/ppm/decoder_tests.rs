use super::*;
use crate::channels::{ticks_to_us, us_to_ticks};
use crate::ppm::waveform::{edges, edgetx_frame_us};

fn feed(decoder: &mut Decoder, timestamps: &[u32]) -> Vec<Decoded> {
    timestamps
        .iter()
        .filter_map(|t| decoder.on_edge(*t))
        .collect()
}

fn frames_of(outcomes: &[Decoded]) -> Vec<ChannelFrame> {
    outcomes
        .iter()
        .filter_map(|o| match o {
            Decoded::Frame(ch) => Some(*ch),
            _ => None,
        })
        .collect()
}

/// Today's checks of the sync-edge and sync-gap releases: early release off, so every
/// locked frame waits for its sync gap (the factory configuration's early release has its
/// own tests, `decoder_early_tests.rs`).
fn sync_only() -> DecoderConfig {
    DecoderConfig {
        early_release_within_us: None,
        ..DecoderConfig::default()
    }
}

const EIGHT: [u16; 8] = [988, 1500, 2012, 1200, 1800, 1000, 2000, 1500];

#[test]
fn locks_on_fifth_clean_frame_and_decodes_values() {
    let mut decoder = Decoder::new(sync_only());
    let outcomes = feed(&mut decoder, &edges(&EIGHT, 22_500, 10, 1_000));
    // The first sync is only seen at frame 2's start and frame 10 has no sync after it, so
    // 8 frame ends: 4 acquiring, then 4 handed out.
    assert_eq!(outcomes.len(), 8);
    assert_eq!(
        outcomes[0],
        Decoded::Acquiring {
            count: 8,
            consistent: 1
        }
    );
    assert_eq!(
        outcomes[3],
        Decoded::Acquiring {
            count: 8,
            consistent: 4
        }
    );
    let frames = frames_of(&outcomes);
    assert_eq!(frames.len(), 4);
    assert_eq!(
        frames[0].as_slice(),
        &[172, 992, 1811, 511, 1472, 191, 1792, 992]
    );
    assert_eq!(decoder.locked_count(), Some(8));
    assert_eq!(decoder.last_periods_us(), &EIGHT);
}

#[test]
fn every_channel_count_from_4_to_16_locks() {
    for count in 4..=16usize {
        let widths: Vec<u16> = (0..count).map(|i| 1000 + 60 * i as u16).collect();
        let mut decoder = Decoder::new(sync_only());
        let outcomes = feed(&mut decoder, &edges(&widths, edgetx_frame_us(count), 8, 0));
        let frames = frames_of(&outcomes);
        assert_eq!(frames.len(), 2, "{count} channels");
        assert_eq!(frames[0].count(), count);
        for (value, width) in frames[1].as_slice().iter().zip(&widths) {
            assert!(ticks_to_us(*value).abs_diff(*width) <= 1);
        }
    }
}

#[test]
fn edgetx_extended_limits_on_one_channel_keep_every_channel() {
    // EdgeTX at ±150 % ("extended limits"): channel outputs ±1536 on its 0.5 µs PPM timer,
    // clamped to PPM_range = 2·768 → 1500 ± 768 µs = 732…2268 µs. One channel at each
    // extreme, the others at ordinary values: all arrive, the extremes at the 11-bit
    // channel range's ends (0 and 2047), the others exact.
    for extreme in [732u16, 2268] {
        let widths = [1500u16, extreme, 1200, 1800, 1000, 2000, 988, 2012];
        let mut decoder = Decoder::new(sync_only());
        let frames = frames_of(&feed(&mut decoder, &edges(&widths, 22_500, 10, 0)));
        assert_eq!(frames.len(), 4, "{extreme} µs");
        let expected_extreme = if extreme < 1500 { 0 } else { 2047 };
        for frame in &frames {
            assert_eq!(frame.get(1), Some(expected_extreme));
            for (index, width) in widths.iter().enumerate().filter(|(i, _)| *i != 1) {
                assert_eq!(
                    frame.get(index),
                    Some(us_to_ticks(*width)),
                    "channel {index}"
                );
            }
        }
    }
}

#[test]
fn periods_outside_700_to_2300_are_clamped_not_dropped() {
    // 600 µs and 2400 µs (still under the 2.5 ms sync) clamp to 700 / 2300 µs.
    let widths = [600u16, 1500, 2400, 1500];
    let mut decoder = Decoder::new(sync_only());
    let frames = frames_of(&feed(&mut decoder, &edges(&widths, 20_000, 7, 0)));
    assert_eq!(frames.len(), 1);
    assert_eq!(decoder.last_periods_us(), &[700, 1500, 2300, 1500]);
    assert_eq!(frames[0].as_slice(), &[0, 992, 2047, 992]);
    assert!(decoder.clamped() >= 2 * 6, "two per frame end seen");
    // The clamp bounds themselves pass unchanged.
    let mut decoder = Decoder::new(sync_only());
    feed(&mut decoder, &edges(&[700, 2300, 700, 2300], 20_000, 7, 0));
    assert_eq!(decoder.last_periods_us(), &[700, 2300, 700, 2300]);
    assert_eq!(decoder.clamped(), 0);
    // Below the glitch threshold a period is not a channel: that frame is dropped.
    let mut decoder = Decoder::new(sync_only());
    let outcomes = feed(&mut decoder, &edges(&[499, 1500, 1500, 1500], 20_000, 3, 0));
    assert_eq!(
        outcomes[0],
        Decoded::Rejected(Reject::ShortPeriod { period_us: 499 })
    );
}

#[test]
fn sync_threshold_is_strictly_above_2500_us() {
    // 16 channels of 2012 µs need 32.2 ms; a 34.7 ms frame leaves a 2.5 ms gap: not a sync,
    // so it reads as a 17th (clamped) channel and those frames are too long.
    let widths = [2012u16; 16];
    let mut decoder = Decoder::new(sync_only());
    let short_rest = 16 * 2012 + 2500;
    assert!(frames_of(&feed(&mut decoder, &edges(&widths, short_rest, 10, 0))).is_empty());
    let mut decoder = Decoder::new(sync_only());
    let frames = frames_of(&feed(&mut decoder, &edges(&widths, short_rest + 1, 10, 0)));
    assert_eq!(frames.len(), 4);
}

#[test]
fn jitter_of_two_microseconds_keeps_lock_and_values() {
    let mut timestamps = edges(&EIGHT, 22_500, 40, 5);
    // Deterministic ±2 µs pattern (EdgeTX's jitter is a few 0.5 µs steps, §2.2).
    for (i, t) in timestamps.iter_mut().enumerate() {
        *t = t.wrapping_add([0u32, 2, 1, 0, 2][i % 5]).wrapping_sub(1);
    }
    let mut decoder = Decoder::new(sync_only());
    let outcomes = feed(&mut decoder, &timestamps);
    let frames = frames_of(&outcomes);
    assert_eq!(frames.len(), 34);
    for frame in &frames {
        for (value, width) in frame.as_slice().iter().zip(&EIGHT) {
            // ±2 µs on each edge is at most ±4 µs on a period, ≈ 6.4 value steps.
            assert!(ticks_to_us(*value).abs_diff(*width) <= 4);
        }
    }
}

#[test]
fn timer_wrap_inside_a_frame_is_seamless() {
    let start = u32::MAX - 30_000;
    let mut decoder = Decoder::new(sync_only());
    let frames = frames_of(&feed(&mut decoder, &edges(&EIGHT, 22_500, 10, start)));
    assert_eq!(frames.len(), 4);
    assert!(frames.iter().all(|f| f.as_slice()[2] == 1811));
}

#[test]
fn a_glitch_drops_one_frame_and_keeps_the_lock() {
    let mut timestamps = edges(&EIGHT, 22_500, 12, 0);
    // A spike 100 µs after a pulse in frame 8 (9 edges per frame).
    let spike = timestamps[8 * 9 + 3] + 100;
    timestamps.insert(8 * 9 + 4, spike);
    let mut decoder = Decoder::new(sync_only());
    let outcomes = feed(&mut decoder, &timestamps);
    assert_eq!(
        outcomes[7],
        Decoded::Rejected(Reject::ShortPeriod { period_us: 100 })
    );
    assert_eq!(frames_of(&outcomes).len(), 5);
    assert_eq!(decoder.locked_count(), Some(8));
}

#[test]
fn count_change_needs_confirmation() {
    let mut timestamps = edges(&EIGHT, 22_500, 8, 0);
    // EIGHT sums to 12 ms, so the next frame starts 10.5 ms after the last pulse.
    let start = timestamps.last().unwrap() + 10_500;
    let six = [1100u16; 6];
    timestamps.extend(edges(&six, 22_500, 8, start));
    let mut decoder = Decoder::new(sync_only());
    let outcomes = feed(&mut decoder, &timestamps);
    let mismatches = outcomes
        .iter()
        .filter(|o| {
            matches!(
                o,
                Decoded::Rejected(Reject::CountMismatch {
                    locked: 8,
                    count: 6
                })
            )
        })
        .count();
    assert_eq!(mismatches, 4);
    let frames = frames_of(&outcomes);
    assert_eq!(frames.last().unwrap().count(), 6);
    assert_eq!(decoder.locked_count(), Some(6));
}

#[test]
fn one_stray_frame_of_another_count_does_not_switch() {
    let mut timestamps = edges(&EIGHT, 22_500, 8, 0);
    let t = *timestamps.last().unwrap();
    timestamps.extend(edges(&[1500u16; 5], 22_500, 1, t + 9_000));
    let t = *timestamps.last().unwrap();
    timestamps.extend(edges(&EIGHT, 22_500, 3, t + 9_000));
    let mut decoder = Decoder::new(sync_only());
    let outcomes = feed(&mut decoder, &timestamps);
    assert!(outcomes.contains(&Decoded::Rejected(Reject::CountMismatch {
        locked: 8,
        count: 5
    })));
    assert_eq!(decoder.locked_count(), Some(8));
    assert_eq!(frames_of(&outcomes).last().unwrap().count(), 8);
}

#[test]
fn loss_after_timeout_reported_once_then_relock() {
    let timestamps = edges(&EIGHT, 22_500, 8, 0);
    let mut decoder = Decoder::new(sync_only());
    feed(&mut decoder, &timestamps);
    // The last frame end seen is the sync edge at the start of frame 8 (7 · 22.5 ms).
    let last_sync = 7 * 22_500;
    assert_eq!(decoder.on_tick(last_sync + 250_000), None);
    assert_eq!(
        decoder.on_tick(last_sync + 250_001),
        Some(Lost { silent_us: 250_001 })
    );
    assert_eq!(decoder.on_tick(last_sync + 400_000), None);
    assert_eq!(decoder.locked_count(), None);
    // The complete frame 8 before the silence counts towards the new lock, so the 7 new
    // frames give 7 frame ends: 4 acquiring, 3 handed out.
    let again = edges(&EIGHT, 22_500, 7, last_sync + 500_000);
    assert_eq!(frames_of(&feed(&mut decoder, &again)).len(), 3);
}

/// Feeds `timestamps`, ticking after each edge as the capture task does and at every
/// release deadline that comes before the next edge; returns (time, outcome) pairs.
fn feed_timed(decoder: &mut Decoder, timestamps: &[u32]) -> Vec<(u32, Decoded)> {
    let mut out = Vec::new();
    for (i, &t) in timestamps.iter().enumerate() {
        if let Some(d) = decoder.on_edge(t) {
            out.push((t, d));
        }
        assert!(decoder.release_due(t).is_none(), "not at the closing edge");
        // After the last edge the line stays quiet.
        let next = timestamps
            .get(i + 1)
            .map_or(u32::MAX, |n| n.wrapping_sub(t));
        if let Some(deadline) = decoder.release_deadline_us()
            && deadline.wrapping_sub(t) < next
        {
            assert!(decoder.release_due(deadline.wrapping_sub(1)).is_none());
            if let Some(d) = decoder.release_due(deadline) {
                out.push((deadline, d));
            }
        }
    }
    out
}

#[test]
fn a_locked_frame_goes_out_a_sync_gap_after_its_last_channel_once() {
    let stream = edges(&EIGHT, 22_500, 10, 1_000);
    let mut decoder = Decoder::new(sync_only());
    let outcomes = feed_timed(&mut decoder, &stream);
    let frames: Vec<(u32, ChannelFrame)> = outcomes
        .iter()
        .filter_map(|(t, o)| match o {
            Decoded::Frame(ch) => Some((*t, *ch)),
            _ => None,
        })
        .collect();
    // Locked at the 5th frame end (its sync edge, as before); frames 6–10 then each go out
    // early, once: five frames, the last one (no sync edge after it) included.
    assert_eq!(frames.len(), 5, "{outcomes:?}");
    let sync_ended = feed(&mut Decoder::new(sync_only()), &stream);
    assert_eq!(frames_of(&sync_ended).len(), 4);
    for (k, (t, ch)) in frames.iter().enumerate().skip(1) {
        // Frame f starts at 1 000 + 22 500·f; its last channel closes after the 8 widths.
        let f = 5 + k as u32;
        let closed = 1_000 + 22_500 * f + EIGHT.iter().map(|w| u32::from(*w)).sum::<u32>();
        assert_eq!(*t, closed + 2_501, "frame {f}");
        // 8 ms before the next frame's first edge, where the sync-edge release came.
        assert_eq!(1_000 + 22_500 * (f + 1) - t, 7_999);
        assert_eq!(ch.as_slice(), &[172, 992, 1811, 511, 1472, 191, 1792, 992]);
    }
}

#[test]
fn a_split_pulse_in_the_last_channel_is_never_released_early() {
    let mut stream = edges(&EIGHT, 22_500, 7, 0);
    // Frame 6, the first after the lock: channel 8 (1 500 µs) split into 800 + 700 by an extra edge, so the
    // frame has nine periods: at its sync edge a count mismatch, as without early release.
    let eighth = 22_500 * 6 + EIGHT[..7].iter().map(|w| u32::from(*w)).sum::<u32>();
    let pos = stream.iter().position(|t| *t == eighth).unwrap();
    stream.insert(pos + 1, eighth + 800);
    stream.push(22_500 * 7);
    let mut decoder = Decoder::new(sync_only());
    let outcomes = feed_timed(&mut decoder, &stream);
    let late: Vec<_> = outcomes.iter().filter(|(t, _)| *t > eighth).collect();
    assert_eq!(
        late,
        vec![&(
            22_500 * 7,
            Decoded::Rejected(Reject::CountMismatch {
                locked: 8,
                count: 9
            })
        )]
    );
}

#[test]
fn too_few_and_too_many_channels_are_rejected() {
    let mut decoder = Decoder::new(sync_only());
    let outcomes = feed(&mut decoder, &edges(&[1500u16; 3], 20_000, 3, 0));
    assert_eq!(
        outcomes[0],
        Decoded::Rejected(Reject::TooFewChannels { count: 3 })
    );
    let mut decoder = Decoder::new(sync_only());
    let outcomes = feed(&mut decoder, &edges(&[1000u16; 17], 40_000, 3, 0));
    assert_eq!(outcomes[0], Decoded::Rejected(Reject::TooManyChannels));
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    fn clean_stream() -> impl Strategy<Value = (Vec<u16>, u32, Vec<i8>)> {
        (4usize..=16).prop_flat_map(|count| {
            (
                proptest::collection::vec(760u16..=2240, count),
                any::<u32>(),
                proptest::collection::vec(-4i8..=4, 400),
            )
        })
    }

    proptest! {
        #[test]
        fn garbage_never_panics_and_frames_are_well_formed(
            steps in proptest::collection::vec(0u32..40_000, 0..600),
            start in any::<u32>(),
        ) {
            let mut decoder = Decoder::new(DecoderConfig::default());
            let mut t = start;
            for step in steps {
                t = t.wrapping_add(step);
                if let Some(Decoded::Frame(ch)) = decoder.on_edge(t) {
                    prop_assert!((4..=16).contains(&ch.count()));
                    prop_assert!(ch.as_slice().iter().all(|v| *v <= 2047));
                }
                let _ = decoder.on_tick(t.wrapping_add(step / 2));
            }
        }

        #[test]
        fn jittered_frames_are_all_delivered_after_lock(
            (widths, start, jitter) in clean_stream(),
        ) {
            let frames = 20;
            let mut timestamps = edges(&widths, edgetx_frame_us(widths.len()), frames, start);
            for (t, j) in timestamps.iter_mut().zip(jitter.iter().cycle()) {
                *t = t.wrapping_add_signed(i32::from(*j));
            }
            let mut decoder = Decoder::new(sync_only());
            let decoded = frames_of(&feed(&mut decoder, &timestamps));
            // 20 frames: 18 frame ends, 4 of them to acquire.
            prop_assert_eq!(decoded.len(), frames - 6);
            for frame in decoded {
                for (value, width) in frame.as_slice().iter().zip(&widths) {
                    // ±4 µs per edge is ±8 µs per period, 1.6 value steps per µs.
                    prop_assert!(value.abs_diff(us_to_ticks(*width)) <= 13);
                }
            }
        }

        #[test]
        fn clean_frames_after_garbage_are_delivered(
            steps in proptest::collection::vec(0u32..30_000, 0..300),
            (widths, start, _jitter) in clean_stream(),
        ) {
            let mut decoder = Decoder::new(DecoderConfig::default());
            let mut t = start;
            for step in steps {
                t = t.wrapping_add(step);
                let _ = decoder.on_edge(t);
            }
            let frames = 15;
            let clean = edges(&widths, edgetx_frame_us(widths.len()), frames, t.wrapping_add(10_000));
            let decoded = frames_of(&feed(&mut decoder, &clean));
            // At worst (no garbage edge before) the first gap only syncs and 4 frame ends
            // go to acquiring, as for a fresh decoder.
            prop_assert!(decoded.len() >= frames - 6, "{} frames", decoded.len());
            for frame in decoded {
                prop_assert_eq!(frame.count(), widths.len());
                for (value, width) in frame.as_slice().iter().zip(&widths) {
                    prop_assert_eq!(*value, us_to_ticks(*width));
                }
            }
        }
    }
}

#[path = "decoder_early_tests.rs"]
mod early;
