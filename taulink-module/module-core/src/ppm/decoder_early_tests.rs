//! The factory configuration's early release (the agreement rule): agreeing frames go at
//! their last channel's closing edge, the others wait for their sync gap, and a split pulse
//! never gets out unless the pilot's frame itself jumped — then only within T of the last
//! frame handed out, and counted.

use super::*;

const T_US: u32 = 200;

fn early_frames(outcomes: &[(u32, Decoded)]) -> Vec<(u32, ChannelFrame)> {
    outcomes
        .iter()
        .filter_map(|(t, o)| match o {
            Decoded::Frame(ch) => Some((*t, *ch)),
            _ => None,
        })
        .collect()
}

/// Frame starts and the edge closing each frame's last channel, for `frames` of `widths`.
fn closing_edge(start: u32, widths: &[u16]) -> u32 {
    start + widths.iter().map(|w| u32::from(*w)).sum::<u32>()
}

#[test]
fn factory_bound_is_below_half_the_glitch_limit() {
    // The split-pulse argument (module doc) needs 2T < glitch_below_us: then a split can
    // only pass when the split channel itself moved by more than T.
    let config = DecoderConfig::default();
    assert_eq!(config.early_release_within_us, Some(T_US));
    assert!(2 * T_US < config.glitch_below_us);
}

#[test]
fn an_agreeing_frame_goes_out_at_its_last_closing_edge() {
    let stream = edges(&EIGHT, 22_500, 10, 1_000);
    let mut decoder = Decoder::new(DecoderConfig::default());
    let frames = early_frames(&feed_timed(&mut decoder, &stream));
    // The first gap only syncs (frame 1), frames 2–5 acquire; the locking frame 6 is held
    // to its sync edge (frame 7's first edge): it has nothing to agree with. Frames 7–10
    // each go at their last channel's closing edge.
    assert_eq!(frames.len(), 5, "{frames:?}");
    assert_eq!(frames[0].0, 1_000 + 22_500 * 6);
    for (k, (t, ch)) in frames.iter().enumerate() {
        assert_eq!(ch.as_slice(), &[172, 992, 1811, 511, 1472, 191, 1792, 992]);
        if k > 0 {
            let start = 1_000 + 22_500 * (5 + k as u32);
            assert_eq!(*t, closing_edge(start, &EIGHT), "frame {}", 6 + k);
        }
    }
    assert_eq!(decoder.early_releases(), 4);
}

#[test]
fn the_first_frame_after_lock_and_after_a_loss_is_held() {
    let mut decoder = Decoder::new(DecoderConfig::default());
    let first = early_frames(&feed_timed(&mut decoder, &edges(&EIGHT, 22_500, 8, 0)));
    // Frames 2–5 acquire, frame 6 locks and goes at its sync edge, 7 and 8 early.
    assert_eq!(first.len(), 3);
    assert_eq!(first[0].0, 22_500 * 6, "at its sync edge");
    assert_eq!(first[1].0, closing_edge(22_500 * 6, &EIGHT), "then early");
    assert_eq!(first[2].0, closing_edge(22_500 * 7, &EIGHT));
    // Silence past the timeout loses the lock; the relock's first frame is held again,
    // though it is the same as the last frame handed out before the loss.
    let restart = 22_500 * 8 + 300_000;
    assert!(decoder.on_tick(restart - 1).is_some());
    let again = early_frames(&feed_timed(
        &mut decoder,
        &edges(&EIGHT, 22_500, 9, restart),
    ));
    assert_eq!(again.len(), 6, "{again:?}");
    assert_eq!(
        (again[0].0 - restart) % 22_500,
        0,
        "at a sync edge: {again:?}"
    );
    for (t, _) in &again[1..] {
        assert_eq!((t - restart) % 22_500, closing_edge(0, &EIGHT));
    }
}

#[test]
fn a_switch_flip_is_held_then_released_at_its_deadline() {
    let mut flipped = EIGHT;
    flipped[5] = 2_000; // channel 6: 1 000 → 2 000 µs
    let mut stream = edges(&EIGHT, 22_500, 7, 0);
    stream.extend(edges(&flipped, 22_500, 3, 22_500 * 7));
    let mut decoder = Decoder::new(DecoderConfig::default());
    let frames = early_frames(&feed_timed(&mut decoder, &stream));
    let flip_at = closing_edge(22_500 * 7, &flipped);
    let flip: Vec<_> = frames.iter().filter(|(t, _)| *t >= flip_at).collect();
    // Held a sync gap (never dropped), with the new value; the next agrees with it again.
    assert_eq!(flip[0].0, flip_at + 2_501);
    assert_eq!(flip[0].1.get(5), Some(us_to_ticks(2_000)));
    assert_eq!(flip[1].0, closing_edge(22_500 * 8, &flipped));
    assert_eq!(flip.len(), 3);
}

#[test]
fn the_split_pulse_of_section_10_is_held_and_dropped() {
    // §10: an extra edge 900 µs into a 1 500 µs throttle (channel 3): periods 900 and 600,
    // both channels; at the eighth closing edge throttle reads 900 µs, far from 1 500: held,
    // the ninth period comes inside the gap, and the frame is dropped.
    let widths = [1_500u16, 1_500, 1_500, 1_500, 988, 988, 1_500, 988];
    let mut stream = edges(&widths, 22_500, 7, 0);
    let throttle_at = 22_500 * 6 + 3_000;
    let pos = stream.iter().position(|t| *t == throttle_at).unwrap();
    stream.insert(pos + 1, throttle_at + 900);
    stream.push(22_500 * 7);
    let mut decoder = Decoder::new(DecoderConfig::default());
    let outcomes = feed_timed(&mut decoder, &stream);
    let late: Vec<_> = outcomes.iter().filter(|(t, _)| *t > throttle_at).collect();
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
fn a_split_released_early_is_counted_and_the_next_frame_is_held() {
    // The one way through: channel 3 really flips 1 000 → 2 000 µs in the frame the split
    // hits, 1 000 µs in, and the channels after it all sit at 1 000 µs, so the shifted frame
    // reads exactly as the last one. It goes early (every channel within T of the last
    // frame — the pilot sees the flip one frame late), the ninth period is counted, and the
    // next frame (the switch back, identical to the released one) must prove its sync gap.
    let calm = [1_500u16, 1_500, 1_000, 1_000, 1_000, 1_000, 1_000, 1_000];
    let mut truth = calm;
    truth[2] = 2_000;
    let mut stream = edges(&calm, 22_500, 7, 0);
    let split_start = 22_500 * 7;
    let mut split = edges(&truth, 22_500, 1, split_start);
    split.insert(3, split_start + 3_000 + 1_000);
    stream.extend(split);
    stream.extend(edges(&calm, 22_500, 2, 22_500 * 8));
    let mut decoder = Decoder::new(DecoderConfig::default());
    let before = decoder.early_releases();
    let outcomes = feed_timed(&mut decoder, &stream);
    let window = |from: u32, to: u32| -> Vec<(u32, Decoded)> {
        outcomes
            .iter()
            .filter(|(t, _)| *t > from && *t <= to)
            .copied()
            .collect()
    };
    let split_out = window(split_start, 22_500 * 8);
    assert_eq!(split_out.len(), 2, "{split_out:?}");
    let Decoded::Frame(released) = split_out[0].1 else {
        panic!("released early: {split_out:?}");
    };
    assert_eq!(released.as_slice(), calm.map(us_to_ticks).as_slice());
    assert_eq!(
        split_out[1],
        (
            22_500 * 8,
            Decoded::Rejected(Reject::GapNotClean { count: 9 })
        )
    );
    let next = window(22_500 * 8, 22_500 * 9);
    assert_eq!(
        next.iter().map(|(t, _)| *t).collect::<Vec<_>>(),
        vec![closing_edge(22_500 * 8, &calm) + 2_501],
        "held for its sync gap"
    );
    assert!(decoder.early_releases() > before);
}

/// A small seeded generator (splitmix64), so the property below is the same every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `lo..=hi`.
    fn range(&mut self, lo: i32, hi: i32) -> i32 {
        lo + (self.next() % (hi - lo + 1) as u64) as i32
    }

    /// A channel as a radio makes it: a switch position or a stick anywhere in ±100 %.
    fn channel(&mut self) -> i32 {
        match self.next() % 4 {
            0 => 988,
            1 => 1_500,
            2 => 2_012,
            _ => self.range(988, 2_012),
        }
    }
}

/// Every channel of `truth` within T of `previous`: a frame a pilot makes between two PPM
/// frames while not flipping a switch or snapping a stick.
fn calm(truth: &[i32], previous: &[i32]) -> bool {
    truth
        .iter()
        .zip(previous)
        .all(|(t, p)| t.abs_diff(*p) <= T_US)
}

/// One case: `previous` repeated until locked and released, then `truth` hit by one extra
/// edge `a_us` into channel `k`, then `truth` again. Returns whether the split frame got
/// out (early).
fn split_case(previous: &[i32], truth: &[i32], k: usize, a_us: i32) -> bool {
    let to_u16 = |v: &[i32]| v.iter().map(|x| *x as u16).collect::<Vec<u16>>();
    let (previous_us, truth_us) = (to_u16(previous), to_u16(truth));
    let n = previous.len();
    let frame_us = edgetx_frame_us(n);
    let start = 7_000;
    let mut stream = edges(&previous_us, frame_us, 7, start);
    let s1 = start + 7 * frame_us;
    let mut split = edges(&truth_us, frame_us, 1, s1);
    let k_start = split[k];
    split.insert(k + 1, k_start + a_us as u32);
    stream.extend(split);
    let (s2, s3) = (s1 + frame_us, s1 + 2 * frame_us);
    stream.extend(edges(&truth_us, frame_us, 2, s2));
    let mut decoder = Decoder::new(DecoderConfig::default());
    let outcomes = feed_timed(&mut decoder, &stream);
    let window = |from: u32, to: u32| -> Vec<(u32, Decoded)> {
        outcomes
            .iter()
            .filter(|(t, _)| *t > from && *t <= to)
            .copied()
            .collect()
    };
    let case = format!("previous {previous:?} truth {truth:?} split {k} at {a_us}");
    // The frame before the split went out, early (it agreed with the locking frame).
    assert_eq!(decoder.locked_count(), Some(n), "{case}");
    let split_out = window(s1, s2);
    let released: Vec<_> = early_frames(&split_out);
    if calm(truth, previous) {
        // A calm frame hides no split: nothing of it gets out.
        assert!(released.is_empty(), "{case}: {split_out:?}");
    }
    for (t, frame) in &released {
        assert!(*t < s2, "only early: {case}");
        for (value, last) in frame.as_slice().iter().zip(previous) {
            // ±1 µs for the µs → tick → µs round trip.
            let us = i32::from(ticks_to_us(*value));
            assert!(us.abs_diff(*last) <= T_US + 1, "{case}: {frame:?}");
        }
    }
    if !released.is_empty() {
        // Counted; for 16 channels the 17th period is one too many (a glitch), so the
        // count stays at 16.
        assert_eq!(
            split_out.last(),
            Some(&(
                s2,
                Decoded::Rejected(Reject::GapNotClean {
                    count: (n + 1).min(MAX_CHANNELS)
                })
            )),
            "{case}"
        );
        // The next frame proves its sync gap before it goes out.
        let next = early_frames(&window(s2, s3));
        assert_eq!(next.len(), 1, "{case}");
        assert_eq!(next[0].0, closing_edge(s2, &truth_us) + 2_501, "{case}");
    }
    // The truth itself always gets out, whole.
    let truth_out = early_frames(&window(s2, s3 + frame_us));
    assert!(!truth_out.is_empty(), "{case}");
    for (_, frame) in truth_out {
        assert_eq!(
            frame.as_slice(),
            truth_us.iter().map(|w| us_to_ticks(*w)).collect::<Vec<_>>(),
            "{case}"
        );
    }
    !released.is_empty()
}

#[test]
fn a_split_pulse_never_releases_a_channel_beyond_t_of_the_last_frame() {
    // Splits at every channel and position over plausible previous frames: calm truths
    // (sticks moving ≤ T), jumpy ones (a switch flips or a stick snaps on the split
    // channel) and truths built to pass the rule (the worst case of the module doc).
    let mut rng = Rng(0x5EED_0017);
    let (mut cases, mut passed) = (0u32, 0u32);
    for round in 0..1_500 {
        let n = rng.range(4, 16) as usize;
        let previous: Vec<i32> = (0..n).map(|_| rng.channel()).collect();
        for k in 0..n {
            let mut truth: Vec<i32> = previous
                .iter()
                .map(|p| (p + rng.range(-(T_US as i32), T_US as i32)).clamp(988, 2_012))
                .collect();
            let mut a = None;
            match round % 3 {
                // Calm: the split channel's own value is split anywhere both parts pass.
                0 => {}
                // Jumpy: the split channel moved anywhere in range.
                1 => truth[k] = rng.channel(),
                // Built to pass: a and b within T of the last k and k+1, the channels after
                // within T of their neighbours' last values.
                _ => {
                    if k + 1 < n {
                        let a_us = previous[k] + rng.range(-(T_US as i32), T_US as i32);
                        let b_us = previous[k + 1] + rng.range(-(T_US as i32), T_US as i32);
                        if a_us + b_us <= 2_012 {
                            truth[k] = a_us + b_us;
                            for j in k + 1..n - 1 {
                                truth[j] = (previous[j + 1]
                                    + rng.range(-(T_US as i32), T_US as i32))
                                .clamp(988, 2_012);
                            }
                            a = Some(a_us);
                        }
                    } else {
                        let a_us = previous[k] + rng.range(-(T_US as i32), T_US as i32);
                        if a_us + 500 <= 2_012 {
                            truth[k] = rng.range(a_us + 500, 2_012);
                            a = Some(a_us);
                        }
                    }
                }
            }
            if truth[k] < 1_000 {
                // Too short to split into two periods above the glitch limit.
                continue;
            }
            let a = a.unwrap_or_else(|| rng.range(500, truth[k] - 500));
            if a < 500 || truth[k] - a < 500 {
                continue;
            }
            cases += 1;
            passed += u32::from(split_case(&previous, &truth, k, a));
        }
    }
    // Not vacuous: thousands of splits, some of them through the rule.
    assert!(cases > 5_000, "{cases} cases");
    assert!(passed > 100, "{passed} of {cases} released early");
}
