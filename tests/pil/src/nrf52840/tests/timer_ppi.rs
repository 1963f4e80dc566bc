//! The PPM capture path (GPIOTE CH0 → PPI CH0 → TIMER1 CAPTURE[0], ppm_in.rs) and the
//! UARTE idle-line detection (RXDRDY → PPI → TIMER CLEAR+START, COMPARE → PPI → STOPRX),
//! register by register as embassy-nrf programs them; PPI groups.

use m4_sim::Bus;

use super::{chip, irq, r, run_to, w};
use crate::wire::Pin;

const GPIOTE: u32 = 0x4000_6000;
const TIMER1: u32 = 0x4000_9000;
const TIMER2: u32 = 0x4000_A000;
const PPI: u32 = 0x4001_F000;
const UARTE0: u32 = 0x4000_2000;
const P1_PIN_CNF_4: u32 = 0x5000_0A10;

/// Timer::new + set_frequency(F1MHz) + start, as ppm_in_task does.
fn timer_1mhz(c: &mut super::Chip, base: u32, t: u64) {
    w(c, base + 0x004, 1, t);
    w(c, base + 0x504, 0, t);
    w(c, base + 0x508, 3, t);
    w(c, base + 0x00C, 1, t);
    w(c, base + 0x510, 4, t);
}

#[test]
fn a_falling_edge_is_captured_to_the_microsecond_whatever_the_cpu_does() {
    let mut c = chip();
    let t = 1_000;
    // Input::new(P1.04, Pull::None): PIN_CNF input, buffer connected.
    w(&mut c, P1_PIN_CNF_4, 0, t);
    // InputChannel::new: CONFIG[0] = Event, HiToLo, P1.04.
    w(
        &mut c,
        GPIOTE + 0x510,
        1 | (4 << 8) | (1 << 13) | (2 << 16),
        t,
    );
    w(&mut c, GPIOTE + 0x100, 0, t);
    timer_1mhz(&mut c, TIMER1, t);
    // Ppi::new_one_to_one(CH0, IN[0], CAPTURE[0]); enable; timer.start().
    w(&mut c, PPI + 0x510, GPIOTE + 0x100, t);
    w(&mut c, PPI + 0x514, TIMER1 + 0x040, t);
    w(&mut c, PPI + 0x504, 1, t);
    w(&mut c, TIMER1 + 0x000, 1, t);
    let pin = Pin::new(1, 4);
    c.drive_input(pin, true, 0);
    c.drive_input(pin, false, 2_501_234);
    c.drive_input(pin, true, 2_801_234);
    c.drive_input(pin, false, 3_601_999);
    run_to(&mut c, 3_000_000);
    assert_eq!(
        r(&mut c, TIMER1 + 0x540, 3_000_000),
        2_500,
        "(2 501 234 − 1 000) ns = 2 500 µs"
    );
    run_to(&mut c, 4_000_000);
    assert_eq!(r(&mut c, TIMER1 + 0x540, 4_000_000), 3_600);
    assert_eq!(r(&mut c, GPIOTE + 0x100, 4_000_000), 1, "EVENTS_IN[0]");
    // CAPTURE[1] by software reads "now" on the same clock.
    w(&mut c, TIMER1 + 0x044, 1, 4_000_000);
    assert_eq!(r(&mut c, TIMER1 + 0x544, 4_000_000), 3_999);
}

#[test]
fn idle_line_detection_stops_the_receiver_20_bit_times_after_the_last_byte() {
    let mut c = chip();
    let t = 0;
    // configure(): 400 kBd (module-core's 0x0666_6000), events cleared; RXD on P0.08.
    w(&mut c, UARTE0 + 0x524, 0x0666_6000, t);
    w(&mut c, UARTE0 + 0x514, 8, t);
    w(&mut c, UARTE0 + 0x500, 8, t);
    // with_idle(): TIMER2 at 16 MHz, CC0 = 0x8000_0000 / (BAUDRATE / 40), COMPARE0→CLEAR|STOP.
    let timeout = 0x8000_0000u32 / (0x0666_6000 / 40);
    assert_eq!(timeout, 800);
    w(&mut c, TIMER2 + 0x004, 1, t);
    w(&mut c, TIMER2 + 0x508, 3, t);
    w(&mut c, TIMER2 + 0x510, 0, t);
    w(&mut c, TIMER2 + 0x540, timeout, t);
    w(&mut c, TIMER2 + 0x200, 1 | (1 << 8), t);
    // CH1: RXDRDY → CLEAR, fork START; CH2: COMPARE[0] → STOPRX.
    w(&mut c, PPI + 0x518, UARTE0 + 0x108, t);
    w(&mut c, PPI + 0x51C, TIMER2 + 0x00C, t);
    w(&mut c, PPI + 0x914, TIMER2 + 0x000, t);
    w(&mut c, PPI + 0x520, TIMER2 + 0x140, t);
    w(&mut c, PPI + 0x524, UARTE0 + 0x004, t);
    w(&mut c, PPI + 0x504, 0b110, t);
    // read_until_idle: 64-byte buffer, ENDRX/ERROR interrupts, STARTRX.
    w(&mut c, UARTE0 + 0x534, 0x2000_1000, t);
    w(&mut c, UARTE0 + 0x538, 64, t);
    w(&mut c, UARTE0 + 0x304, (1 << 4) | (1 << 9), t);
    w(&mut c, UARTE0 + 0x000, 1, t);
    // A 3-byte frame, one byte each 25 µs (10 bits at 400 kBd).
    for (i, b) in [0xC8u8, 0x18, 0x16].into_iter().enumerate() {
        c.uart_receive(1, b, 100_000 + 25_000 * i as u64);
    }
    run_to(&mut c, 199_999);
    assert!(!irq(&c, 2));
    // Last byte at 150 µs; 800 ticks of 62.5 ns = 50 µs later the PPI stops the receiver.
    run_to(&mut c, 200_000);
    assert!(irq(&c, 2), "ENDRX on IRQ 2 = UARTE0");
    assert_eq!(r(&mut c, UARTE0 + 0x53C, 200_000), 3, "RXD.AMOUNT");
    assert_eq!(r(&mut c, UARTE0 + 0x144, 200_000), 1, "RXTO");
    assert_eq!(c.ram()[0x1000..0x1003], [0xC8, 0x18, 0x16]);
}

#[test]
fn channel_groups_enable_and_disable_their_channels() {
    let mut c = chip();
    w(&mut c, PPI + 0x800, 0b1010, 0);
    w(&mut c, PPI + 0x000, 1, 0);
    assert_eq!(r(&mut c, PPI + 0x500, 0), 0b1010);
    w(&mut c, PPI + 0x004, 1, 0);
    assert_eq!(r(&mut c, PPI + 0x500, 0), 0);
}

#[test]
fn compare_clear_short_makes_a_periodic_event() {
    let mut c = chip();
    timer_1mhz(&mut c, TIMER1, 0);
    w(&mut c, TIMER1 + 0x540, 1000, 0);
    w(&mut c, TIMER1 + 0x200, 1, 0);
    w(&mut c, TIMER1 + 0x000, 1, 0);
    assert_eq!(c.next_event_ns(), 1_000_000);
    run_to(&mut c, 1_000_000);
    w(&mut c, TIMER1 + 0x140, 0, 1_000_000);
    assert_eq!(c.next_event_ns(), 2_000_000);
}
