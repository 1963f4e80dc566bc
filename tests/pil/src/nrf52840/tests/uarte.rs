//! UARTE as the JR line and the HM-10 use it: transmit timing at the register's real baud
//! rate, ENDTX before the last stop bit, receive into the buffer, the RX FIFO and overrun,
//! STOPRX, and disabling mid-byte.

use m4_sim::{Bus, Width};

use super::{chip, irq, r, run_to, w};
use crate::nrf52840::uarte_bit_ps;
use crate::wire::{Drive, Pin};

const UARTE0: u32 = 0x4000_2000;
const BUF: u32 = 0x2000_0400;

#[test]
fn baud_register_gives_whole_16_mhz_cycles_per_bit() {
    // The PS's "actual rate" column: 115 200 → 115 108 Bd, 921 600 → 941 176 Bd.
    assert_eq!(uarte_bit_ps(0x01D6_0000), Some(139 * 62_500));
    assert_eq!(uarte_bit_ps(0x0F00_0000), Some(17 * 62_500));
    assert_eq!(uarte_bit_ps(0x0027_5000), Some(1667 * 62_500));
    // module-core's CRSF value 0x0666_6000 is exactly 400 kBd; its 921 600 value runs at
    // 16 MHz / 17 = 941 176 Bd, 2.1 % fast.
    assert_eq!(uarte_bit_ps(0x0666_6000), Some(40 * 62_500));
    assert_eq!(uarte_bit_ps(0x0EBE_D000), Some(17 * 62_500));
    assert_eq!(uarte_bit_ps(0), None);
}

/// UarteTx::new(UARTE0, P0.06, 400 kBd) then write(bytes).
fn send(c: &mut super::Chip, bytes: &[u8], t: u64) {
    w(c, UARTE0 + 0x524, 0x0666_6000, t);
    w(c, 0x5000_0508, 1 << 6, t); // txd.set_high()
    w(c, 0x5000_0718, 3, t); // PIN_CNF[6]: output, input disconnected
    w(c, UARTE0 + 0x50C, 6, t);
    w(c, UARTE0 + 0x500, 8, t);
    for (i, &b) in bytes.iter().enumerate() {
        c.write(BUF + i as u32, Width::Byte, u32::from(b), t)
            .unwrap();
    }
    w(c, UARTE0 + 0x544, BUF, t);
    w(c, UARTE0 + 0x548, bytes.len() as u32, t);
    w(c, UARTE0 + 0x120, 0, t);
    w(c, UARTE0 + 0x304, 1 << 8, t);
    w(c, UARTE0 + 0x008, 1, t);
}

#[test]
fn bytes_reach_the_board_at_the_end_of_their_stop_bit() {
    let mut c = chip();
    send(&mut c, &[0xEA, 0x04, 0x28], 0);
    assert_eq!(r(&mut c, UARTE0 + 0x150, 0), 1, "TXSTARTED");
    // 10 bits of 2.5 µs: 25 µs a byte. ENDTX when the last byte leaves RAM, at 50 µs.
    run_to(&mut c, 49_999);
    assert!(!irq(&c, 2));
    run_to(&mut c, 50_000);
    assert!(irq(&c, 2), "ENDTX");
    assert_eq!(r(&mut c, UARTE0 + 0x54C, 50_000), 3, "TXD.AMOUNT");
    run_to(&mut c, 75_000);
    assert_eq!(
        c.outside().uart,
        vec![(1, 0xEA, 25_000), (1, 0x04, 50_000), (1, 0x28, 75_000)]
    );
}

#[test]
fn the_txd_pin_idles_high_while_enabled_and_is_released_after() {
    let mut c = chip();
    send(&mut c, &[0x55], 0);
    run_to(&mut c, 100_000);
    w(&mut c, UARTE0 + 0x500, 0, 100_000);
    let p6: Vec<Drive> = c
        .outside()
        .driven
        .iter()
        .filter(|d| d.0 == Pin::new(0, 6))
        .map(|d| d.1)
        .collect();
    // GPIO output high, then the UARTE holds it high: one change only, and it stays High
    // once GPIO takes it back (OUT = 1).
    assert_eq!(p6, vec![Drive::High]);
}

#[test]
fn disabling_mid_byte_cuts_it() {
    let mut c = chip();
    send(&mut c, &[0x01, 0x02], 0);
    w(&mut c, UARTE0 + 0x500, 0, 30_000);
    run_to(&mut c, 100_000);
    assert_eq!(c.outside().uart, vec![(1, 0x01, 25_000)]);
    assert!(c.records().notes().iter().any(|n| n.what.contains("cut")));
}

fn receiver(c: &mut super::Chip, len: u32, t: u64) {
    w(c, UARTE0 + 0x524, 0x01D6_0000, t);
    w(c, UARTE0 + 0x514, 8, t);
    w(c, UARTE0 + 0x500, 8, t);
    w(c, UARTE0 + 0x534, BUF, t);
    w(c, UARTE0 + 0x538, len, t);
    w(c, UARTE0 + 0x304, (1 << 4) | (1 << 9), t);
    w(c, UARTE0 + 0x000, 1, t);
}

#[test]
fn endrx_when_the_buffer_is_full() {
    let mut c = chip();
    receiver(&mut c, 2, 0);
    assert_eq!(r(&mut c, UARTE0 + 0x14C, 0), 1, "RXSTARTED");
    assert_eq!(c.uart_rx_baud(1).map(|b| b.round()), Some(115_108.0));
    c.uart_receive(1, 0x4F, 10_000);
    c.uart_receive(1, 0x4B, 20_000);
    run_to(&mut c, 15_000);
    assert_eq!(r(&mut c, UARTE0 + 0x108, 15_000), 1, "RXDRDY");
    assert!(!irq(&c, 2));
    run_to(&mut c, 20_000);
    assert!(irq(&c, 2));
    assert_eq!(c.ram()[0x400..0x402], *b"OK");
}

#[test]
fn four_bytes_wait_in_the_fifo_a_fifth_overruns() {
    let mut c = chip();
    receiver(&mut c, 1, 0);
    for i in 0..6u8 {
        c.uart_receive(1, 0x30 + i, 10_000 * (u64::from(i) + 1));
    }
    run_to(&mut c, 60_000);
    assert_eq!(r(&mut c, UARTE0 + 0x480, 60_000), 1, "ERRORSRC.OVERRUN");
    assert_eq!(r(&mut c, UARTE0 + 0x124, 60_000), 1, "ERROR");
    // STARTRX drains the FIFO into the new buffer.
    w(&mut c, UARTE0 + 0x534, BUF + 0x10, 60_000);
    w(&mut c, UARTE0 + 0x538, 8, 60_000);
    w(&mut c, UARTE0 + 0x000, 1, 60_000);
    assert_eq!(r(&mut c, UARTE0 + 0x53C, 60_000), 4);
    assert_eq!(c.ram()[0x410..0x414], [0x31, 0x32, 0x33, 0x34]);
}

#[test]
fn stoprx_ends_the_buffer_then_times_out() {
    let mut c = chip();
    receiver(&mut c, 8, 0);
    c.uart_receive(1, 0x11, 5_000);
    run_to(&mut c, 6_000);
    w(&mut c, UARTE0 + 0x004, 1, 6_000);
    assert_eq!(r(&mut c, UARTE0 + 0x110, 6_000), 1, "ENDRX");
    assert_eq!(r(&mut c, UARTE0 + 0x144, 6_000), 1, "RXTO");
    assert_eq!(r(&mut c, UARTE0 + 0x53C, 6_000), 1);
    c.uart_receive(1, 0x22, 7_000);
    run_to(&mut c, 8_000);
    assert_eq!(
        r(&mut c, UARTE0 + 0x53C, 8_000),
        1,
        "a stopped receiver drops bytes"
    );
}

#[test]
fn the_jr_line_turns_round_receive_then_send_then_receive() {
    let mut c = chip();
    // UarteRx on P0.08 (CRSF, 400 kBd), a frame in, then dropped: ENABLE 0, PSEL back.
    w(&mut c, UARTE0 + 0x524, 0x0666_6000, 0);
    w(&mut c, UARTE0 + 0x514, 8, 0);
    w(&mut c, UARTE0 + 0x500, 8, 0);
    w(&mut c, UARTE0 + 0x534, BUF, 0);
    w(&mut c, UARTE0 + 0x538, 64, 0);
    w(&mut c, UARTE0 + 0x000, 1, 0);
    c.uart_receive(1, 0xC8, 25_000);
    run_to(&mut c, 30_000);
    w(&mut c, UARTE0 + 0x004, 1, 30_000);
    w(&mut c, UARTE0 + 0x500, 0, 30_000);
    // The radio's own transmission is not read back: the receiver is gone.
    c.uart_receive(1, 0xEE, 90_000);
    // UarteTx on P0.06 for the reply, then dropped.
    send(&mut c, &[0xEA], 40_000);
    run_to(&mut c, 100_000);
    w(&mut c, UARTE0 + 0x500, 0, 100_000);
    assert_eq!(c.outside().uart, vec![(1, 0xEA, 65_000)]);
    assert_eq!(c.ram()[0x400], 0xEA, "the TX buffer");
    assert_eq!(
        r(&mut c, UARTE0 + 0x53C, 100_000),
        1,
        "only the radio's byte was received"
    );
}

#[test]
fn the_hm10_rate_9600_takes_1_04_ms_a_byte() {
    let mut c = chip();
    w(&mut c, 0x4002_8524, 0x0027_5000, 0);
    w(&mut c, 0x4002_850C, 32 + 11, 0);
    w(&mut c, 0x4002_8500, 8, 0);
    c.write(BUF, Width::Byte, u32::from(b'A'), 0).unwrap();
    w(&mut c, 0x4002_8544, BUF, 0);
    w(&mut c, 0x4002_8548, 1, 0);
    w(&mut c, 0x4002_8008, 1, 0);
    run_to(&mut c, 2_000_000);
    // 10 bits of 1667 cycles at 16 MHz.
    assert_eq!(c.outside().uart, vec![(2, b'A', 1_041_875)]);
}

#[test]
fn a_sender_a_few_percent_off_is_read_right_far_off_it_is_a_framing_error() {
    use crate::nrf52840::uarte_resample as resample;
    let rx = uarte_bit_ps(0x0EBE_D000).unwrap(); // 941 176 Bd
    // EdgeTX at 921 600 Bd into the module's "921 600" setting: 2.1 % apart, intact.
    for byte in [0x00, 0x55, 0xC8, 0xFF] {
        assert_eq!(resample(byte, 921_600.0, rx), (byte, true));
    }
    // A 400 kBd CRSF byte into a 115 200 Bd receiver: garbage.
    let (value, framed) = resample(0xC8, 400_000.0, uarte_bit_ps(0x01D6_0000).unwrap());
    assert!(value != 0xC8 || !framed);
    // Through the chip: the ERROR event and ERRORSRC.FRAMING.
    let mut c = chip();
    receiver(&mut c, 4, 0);
    c.uart_receive_at_baud(1, 0x00, 57_600.0, 100_000);
    run_to(&mut c, 100_000);
    assert_eq!(r(&mut c, UARTE0 + 0x480, 100_000), 1 << 2);
    assert_eq!(r(&mut c, UARTE0 + 0x124, 100_000), 1);
}
