//! The module's PPM input decoder (`module_core::ppm::decoder`): fuzz bytes become the
//! intervals between captured edges (so timestamps wrap like the hardware timer) and loss
//! checks at fuzzed times, under the default limits or fuzzed ones.
//!
//! Invariants: a handed-out frame has the locked channel count (4..=16 by default, never
//! more than 16), values in the link's 11-bit range, and periods inside the configured
//! channel limits; a lock is only reported lost when there was one.
#![no_main]

use libfuzzer_sys::fuzz_target;
use module_core::channels::{MAX_CHANNELS, TICKS_MAX};
use module_core::ppm::{Decoded, Decoder, DecoderConfig};
use taulink_fuzz::Input;

fuzz_target!(|data: &[u8]| {
    let mut input = Input::new(data);
    let config = if input.bool() {
        DecoderConfig::default()
    } else {
        DecoderConfig {
            sync_min_us: u32::from(input.u16()),
            glitch_below_us: u32::from(input.u16()),
            channel_min_us: u32::from(input.u16()),
            channel_max_us: u32::from(input.u16()),
            min_channels: usize::from(input.u8() % 20),
            lock_frames: input.u8() % 8,
            loss_timeout_us: input.u32(),
            early_release_within_us: input.bool().then(|| u32::from(input.u16())),
        }
    };
    let mut decoder = Decoder::new(config);
    let mut now = input.u32();
    while !input.is_empty() {
        let step = input.u16();
        if step == 0xFFFF {
            // A loss check somewhere between this edge and the next.
            let at = now.wrapping_add(input.u32());
            let locked = decoder.locked_count().is_some();
            if decoder.on_tick(at).is_some() {
                assert!(locked, "lost a lock it did not have");
                assert_eq!(decoder.locked_count(), None);
            }
            continue;
        }
        // Mostly channel-sized steps; a high bit stretches one into a sync gap or beyond.
        now = now.wrapping_add(u32::from(step) << (input.u8() % 4 * 3));
        if let Some(Decoded::Frame(channels)) = decoder.on_edge(now) {
            let count = decoder.locked_count().expect("frames only when locked");
            assert_eq!(channels.count(), count);
            assert!(count <= MAX_CHANNELS && count >= config.min_channels);
            assert!(channels.as_slice().iter().all(|&v| v <= TICKS_MAX));
            let periods = decoder.last_periods_us();
            assert_eq!(periods.len(), count);
            // Periods are clamped into the channel range (a fuzzed config may give an empty
            // range, min > max: then only the upper bound is defined).
            for &p in periods {
                let p = u32::from(p);
                assert!(p <= config.channel_max_us.max(config.channel_min_us));
                if config.channel_min_us <= config.channel_max_us {
                    assert!(
                        p >= config.channel_min_us,
                        "{p} below {}",
                        config.channel_min_us
                    );
                }
            }
        }
    }
});
