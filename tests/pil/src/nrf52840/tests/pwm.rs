//! PWM0 as the receiver role's PPM output plays a frame (ppm_out.rs): 1 µs ticks, waveform
//! load, one sequence played once, every edge at its time on P1.06.

use m4_sim::{Bus, Width};

use super::{chip, irq, r, run_to, w};
use crate::wire::{Drive, Pin};

const PWM0: u32 = 0x4001_C000;
const SEQ: u32 = 0x2000_0C00;

/// SequencePwm::new_1ch(PWM0, P1.06, Up, Div16, Waveform, idle high).
fn setup(c: &mut super::Chip, t: u64) {
    w(c, 0x5000_0808, 1 << 6, t); // P1 OUTSET: idle level high
    w(c, 0x5000_0300 + 0x700 + 4 * 6, 3, t); // P1 PIN_CNF[6]: output, disconnected input
    w(c, PWM0 + 0x560, 32 + 6, t);
    w(c, PWM0 + 0x308, 0xFFFF_FFFF, t);
    w(c, PWM0 + 0x200, 0, t);
    w(c, PWM0 + 0x510, 3, t); // DECODER: Waveform, RefreshCount
    w(c, PWM0 + 0x504, 0, t);
    w(c, PWM0 + 0x50C, 4, t); // PRESCALER /16: 1 MHz
    w(c, PWM0 + 0x508, 1000, t);
}

/// SingleSequencer::start(Times(1)): both sequences on the words, LOOP 1, SEQSTART[1].
fn play(c: &mut super::Chip, words: &[u16], t: u64) {
    for (i, &word) in words.iter().enumerate() {
        c.write(SEQ + 2 * i as u32, Width::Half, u32::from(word), t)
            .unwrap();
    }
    for n in 0..2 {
        let seq = PWM0 + 0x520 + 0x20 * n;
        w(c, seq + 0x8, 0, t);
        w(c, seq + 0xC, 0, t);
        w(c, seq, SEQ, t);
        w(c, seq + 0x4, words.len() as u32, t);
    }
    w(c, PWM0 + 0x500, 1, t);
    w(c, PWM0 + 0x514, 1, t);
    w(c, PWM0 + 0x00C, 1, t);
}

fn edges(c: &super::Chip) -> Vec<(Drive, u64)> {
    c.outside()
        .driven
        .iter()
        .filter(|d| d.0 == Pin::new(1, 6))
        .map(|d| (d.1, d.2))
        .collect()
}

#[test]
fn a_ppm_frame_plays_as_low_pulses_with_exact_edges() {
    let mut c = chip();
    setup(&mut c, 0);
    // module-core's write_waveform with pulse_high = false: compare = 300 (RisingEdge: low
    // for 300 µs, then high), COUNTERTOP = slot length; a tail slot with compare 0.
    let words = [300, 0, 0, 1500, 300, 0, 0, 1000, 0, 0, 0, 2000];
    let t0 = 10_000;
    play(&mut c, &words, t0);
    run_to(&mut c, t0 + 4_000_000);
    assert_eq!(
        edges(&c),
        vec![
            (Drive::High, 0),
            (Drive::Low, t0),
            (Drive::High, t0 + 300_000),
            (Drive::Low, t0 + 1_500_000),
            (Drive::High, t0 + 1_800_000),
        ]
    );
    // SEQEND[1] and LOOPSDONE after the three slots (4.5 ms); the tail value holds.
    assert_eq!(r(&mut c, PWM0 + 0x114, t0 + 4_499_999), 0);
    run_to(&mut c, t0 + 4_500_000);
    assert_eq!(r(&mut c, PWM0 + 0x114, t0 + 4_500_000), 1, "SEQEND[1]");
    assert_eq!(r(&mut c, PWM0 + 0x11C, t0 + 4_500_000), 1, "LOOPSDONE");
    assert_eq!(
        c.next_event_ns(),
        u64::MAX,
        "a constant output needs no more periods"
    );
    assert!(!irq(&c, 28));
}

#[test]
fn stop_ends_at_the_period_end_and_hands_the_pin_back_to_gpio() {
    let mut c = chip();
    setup(&mut c, 0);
    play(&mut c, &[300, 0, 0, 1000], 0);
    // Sequencer::stop (on drop): SHORTS 0, STOP, ENABLE 0 — here STOP alone first.
    w(&mut c, PWM0 + 0x004, 1, 500_000);
    run_to(&mut c, 999_999);
    assert_eq!(r(&mut c, PWM0 + 0x104, 999_999), 0);
    run_to(&mut c, 1_000_000);
    assert_eq!(r(&mut c, PWM0 + 0x104, 1_000_000), 1, "STOPPED");
    // GPIO OUT is high: the pin idles high.
    assert_eq!(edges(&c).last(), Some(&(Drive::High, 300_000)));
}

#[test]
fn falling_edge_polarity_starts_high() {
    let mut c = chip();
    setup(&mut c, 0);
    w(&mut c, 0x5000_080C, 1 << 6, 0); // GPIO OUT low, so the first High shows
    play(&mut c, &[0x8000 | 250, 0, 0, 1000], 1_000);
    run_to(&mut c, 600_000);
    assert_eq!(
        edges(&c)[1..],
        [(Drive::Low, 0), (Drive::High, 1_000), (Drive::Low, 251_000)]
    );
}
