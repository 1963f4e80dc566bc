use super::*;
use crate::channels::us_to_ticks;
use crate::ppm::decoder::{Decoded, Decoder, DecoderConfig};

fn channels_us(widths: &[u16]) -> ChannelFrame {
    let values: Vec<u16> = widths.iter().map(|w| us_to_ticks(*w)).collect();
    ChannelFrame::from_ticks(&values)
}

/// Edge timestamps of the pulse starts (what the decoder captures) for consecutive frames.
fn pulse_edges(frames: &[Frame]) -> Vec<u32> {
    let mut t = 0u32;
    let mut edges = Vec::new();
    for frame in frames {
        for slot in frame.slots() {
            if slot.pulse_us > 0 {
                edges.push(t);
            }
            t += u32::from(slot.period_us);
        }
    }
    edges
}

fn check_invariants(frame: &Frame, config: &EncoderConfig) {
    let slots = frame.slots();
    assert_eq!(slots.len(), config.channels + 2);
    let (channels, rest) = slots.split_at(config.channels);
    for slot in channels {
        assert_eq!(slot.pulse_us, config.pulse_us);
        assert!((config.min_width_us..=config.max_width_us).contains(&slot.period_us));
    }
    let sync_us = u32::from(rest[0].period_us) + u32::from(rest[1].period_us);
    assert!(sync_us >= 4_500, "sync {sync_us} µs");
    assert_eq!(rest[0].pulse_us, config.pulse_us);
    assert_eq!(rest[1].pulse_us, 0);
    assert!(frame.length_us() >= config.frame_us);
    for slot in slots {
        assert!(u32::from(slot.period_us) <= MAX_SLOT_US && slot.period_us >= 3);
        assert!(slot.pulse_us < slot.period_us);
    }
}

#[test]
fn default_frame_is_22_5_ms_with_eight_channels() {
    let config = EncoderConfig::default();
    let mut encoder = Encoder::new(config).unwrap();
    assert_eq!(
        encoder.next_frame(),
        None,
        "no pulses before the first values"
    );
    encoder.set_channels(&channels_us(&[
        1000, 1100, 1200, 1300, 1400, 1500, 1600, 1700,
    ]));
    let frame = encoder.next_frame().unwrap();
    check_invariants(&frame, &config);
    assert_eq!(frame.length_us(), 22_500);
    // Σ = 10 800 µs ⇒ 11 700 µs of sync: a 10 700 µs pulsed slot plus the 1 ms tail.
    assert_eq!(
        frame.slots()[8],
        Slot {
            period_us: 10_700,
            pulse_us: 300
        }
    );
    assert_eq!(
        frame.slots()[9],
        Slot {
            period_us: 1_000,
            pulse_us: 0
        }
    );
}

#[test]
fn full_deflection_keeps_a_sync_of_at_least_4_5_ms() {
    let config = EncoderConfig::default();
    let mut encoder = Encoder::new(config).unwrap();
    encoder.set_channels(&ChannelFrame::from_ticks(&[2047; 8]));
    let frame = encoder.next_frame().unwrap();
    check_invariants(&frame, &config);
    // 2047 → 2159 µs, clipped to 2100: 16 800 µs of channels, 5 700 µs of sync.
    assert_eq!(frame.slots()[0].period_us, 2_100);
    assert_eq!(frame.length_us(), 22_500);
    // A frame too short for the channels grows instead of cutting the sync.
    let tight = EncoderConfig {
        frame_us: 18_000,
        ..config
    };
    let mut encoder = Encoder::new(tight).unwrap();
    encoder.set_channels(&ChannelFrame::from_ticks(&[2047; 8]));
    let frame = encoder.next_frame().unwrap();
    assert_eq!(frame.length_us(), 16_800 + 4_500);
}

#[test]
fn new_values_only_at_frame_boundaries() {
    let mut encoder = Encoder::new(EncoderConfig::default()).unwrap();
    encoder.set_channels(&channels_us(&[1000; 8]));
    let first = encoder.next_frame().unwrap();
    encoder.set_channels(&channels_us(&[1200; 8]));
    encoder.set_channels(&channels_us(&[1400; 8]));
    // The frame already handed out is a value: it cannot change under the PWM.
    assert_eq!(first.slots()[0].period_us, 1000);
    let second = encoder.next_frame().unwrap();
    assert!(second.slots()[..8].iter().all(|s| s.period_us == 1400));
    let third = encoder.next_frame().unwrap();
    assert_eq!(second, third, "without news the same frame repeats");
}

#[test]
fn failsafe_hold_last_or_stop() {
    let mut hold = Encoder::new(EncoderConfig {
        failsafe: FailsafeOutput::HoldLast,
        ..EncoderConfig::default()
    })
    .unwrap();
    hold.set_channels(&channels_us(&[1300; 8]));
    let before = hold.next_frame().unwrap();
    hold.set_failsafe(true);
    assert_eq!(hold.next_frame(), Some(before));

    // The default: a lost link must not hold the throttle.
    let mut stop = Encoder::new(EncoderConfig::default()).unwrap();
    stop.set_channels(&channels_us(&[1300; 8]));
    assert!(stop.next_frame().is_some());
    stop.set_failsafe(true);
    assert_eq!(stop.next_frame(), None);
    assert_eq!(stop.next_frame(), None);
    stop.set_channels(&channels_us(&[1700; 8]));
    assert_eq!(stop.next_frame().unwrap().slots()[3].period_us, 1700);
}

#[test]
fn waveform_words_follow_the_pwm_layout() {
    let mut encoder = Encoder::new(EncoderConfig::default()).unwrap();
    encoder.set_channels(&channels_us(&[1500; 8]));
    let frame = encoder.next_frame().unwrap();
    let mut words = [0u16; 40];
    assert_eq!(frame.write_waveform(&mut words, false), Some(40));
    assert_eq!(&words[..4], &[300, 0, 0, 1500]);
    assert_eq!(&words[32..36], &[300, 0, 0, 22_500 - 12_000 - 1_000]);
    assert_eq!(&words[36..40], &[0, 0, 0, 1000]);
    assert_eq!(frame.write_waveform(&mut words, true), Some(40));
    assert_eq!(words[0], 0x8000 | 300);
    assert_eq!(words[36], 0, "the tail never pulses in either polarity");
    assert_eq!(frame.write_waveform(&mut [0u16; 39], false), None);
}

#[test]
fn decoder_reads_back_what_the_encoder_sends() {
    let widths = [988u16, 1100, 1250, 1500, 1640, 1800, 1950, 2012];
    let mut encoder = Encoder::new(EncoderConfig::default()).unwrap();
    encoder.set_channels(&channels_us(&widths));
    let frames: Vec<Frame> = (0..8).map(|_| encoder.next_frame().unwrap()).collect();
    let mut decoder = Decoder::new(DecoderConfig::default());
    let decoded: Vec<ChannelFrame> = pulse_edges(&frames)
        .into_iter()
        .filter_map(|t| match decoder.on_edge(t) {
            Some(Decoded::Frame(ch)) => Some(ch),
            _ => None,
        })
        .collect();
    // 8 frames: the first gap only syncs, 4 to lock; the last frame has no gap after it but
    // agrees with the one before, so it goes out at its last channel's closing edge.
    assert_eq!(decoded.len(), 3);
    assert!(decoded.iter().all(|d| *d == channels_us(&widths)));
}

#[test]
fn bad_configs_are_refused() {
    let base = EncoderConfig::default();
    assert_eq!(
        Encoder::new(EncoderConfig {
            channels: 17,
            ..base
        })
        .unwrap_err(),
        ConfigError::ChannelCount
    );
    assert_eq!(
        Encoder::new(EncoderConfig {
            pulse_us: 900,
            ..base
        })
        .unwrap_err(),
        ConfigError::PulseTooLong
    );
    assert_eq!(
        Encoder::new(EncoderConfig {
            channels: 1,
            frame_us: 40_000,
            ..base
        })
        .unwrap_err(),
        ConfigError::SlotTooLong
    );
    assert_eq!(
        Encoder::new(EncoderConfig {
            idle_tail_us: 0,
            ..base
        })
        .unwrap_err(),
        ConfigError::NoIdleTail
    );
}

proptest::proptest! {
    #[test]
    fn any_values_keep_the_invariants(values in proptest::collection::vec(0u16..4096, 8)) {
        let config = EncoderConfig::default();
        let mut encoder = Encoder::new(config).unwrap();
        encoder.set_channels(&ChannelFrame::from_ticks(&values));
        let frame = encoder.next_frame().unwrap();
        check_invariants(&frame, &config);
        proptest::prop_assert_eq!(frame.length_us(), 22_500);
    }
}
