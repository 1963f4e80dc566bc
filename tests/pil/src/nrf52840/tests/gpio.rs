//! GPIO as embassy-nrf's `Output`/`Input` drive it, SENSE/LATCH/DETECT with GPIOTE's PORT
//! event (the radio's nIRQ wait), and the NFC pads.

use m4_sim::Bus;
use m4_sim::bus::ResetCause;

use super::{chip, irq, r, run_to, w};
use crate::nrf52840::uicr;
use crate::wire::{Drive, Pin, Pull};

const P0: u32 = 0x5000_0000;
const P1: u32 = 0x5000_0300;
const GPIOTE: u32 = 0x4000_6000;

fn pin_cnf(port: u32, n: u32) -> u32 {
    port + 0x700 + 4 * n
}

#[test]
fn output_new_sets_the_level_then_the_direction() {
    let mut c = chip();
    // Output::new(P0.24, High, Standard): OUTSET, then PIN_CNF = output.
    w(&mut c, P0 + 0x508, 1 << 24, 100);
    assert!(c.outside().driven.is_empty(), "an input does not drive");
    w(&mut c, pin_cnf(P0, 24), 3, 200);
    w(&mut c, P0 + 0x50C, 1 << 24, 300);
    assert_eq!(
        c.outside().driven,
        vec![
            (Pin::new(0, 24), Drive::High, 200),
            (Pin::new(0, 24), Drive::Low, 300)
        ]
    );
}

#[test]
fn inputs_read_the_board_else_the_queue_else_the_pull() {
    let mut c = chip();
    // Input::new(P1.15, Pull::Up): input, buffer connected, pull-up.
    w(&mut c, pin_cnf(P1, 15), 0xC, 0);
    assert_eq!(
        c.outside().driven,
        vec![(Pin::new(1, 15), Drive::Released(Pull::Up), 0)]
    );
    assert_eq!(r(&mut c, P1 + 0x510, 0) >> 15 & 1, 1, "pulled up");
    c.drive_input(Pin::new(1, 15), false, 1_000);
    assert_eq!(
        r(&mut c, P1 + 0x510, 1_000) >> 15 & 1,
        0,
        "the button pressed"
    );
    c.outside_mut().levels.insert(Pin::new(1, 15), true);
    assert_eq!(
        r(&mut c, P1 + 0x510, 2_000) >> 15 & 1,
        1,
        "the board's answer first"
    );
    // A disconnected input buffer reads 0.
    w(&mut c, pin_cnf(P1, 15), 0xE, 3_000);
    assert_eq!(r(&mut c, P1 + 0x510, 3_000), 0);
}

#[test]
fn sense_low_latches_and_raises_port_in_ldetect_mode() {
    let mut c = chip();
    // gpiote::init: DETECTMODE = LDetect, LATCH cleared, PORT interrupt on.
    w(&mut c, P0 + 0x524, 1, 0);
    w(&mut c, P0 + 0x520, 0xFFFF_FFFF, 0);
    w(&mut c, GPIOTE + 0x304, 1 << 31, 0);
    // Input::new(P0.11, Pull::Up), then wait_for_low(): SENSE = Low.
    w(&mut c, pin_cnf(P0, 11), 0xC, 0);
    w(&mut c, pin_cnf(P0, 11), 0xC | (3 << 16), 10);
    assert!(!irq(&c, 6));
    c.drive_input(Pin::new(0, 11), false, 5_000);
    run_to(&mut c, 4_999);
    assert!(!irq(&c, 6));
    run_to(&mut c, 5_000);
    assert!(irq(&c, 6), "PORT on IRQ 6 = GPIOTE");
    assert_eq!(r(&mut c, P0 + 0x520, 5_000), 1 << 11, "LATCH");
    // The handler: SENSE off for latched pins, LATCH cleared, EVENTS_PORT cleared.
    w(&mut c, GPIOTE + 0x17C, 0, 6_000);
    w(&mut c, pin_cnf(P0, 11), 0xC, 6_000);
    w(&mut c, P0 + 0x520, 1 << 11, 6_000);
    assert_eq!(r(&mut c, P0 + 0x520, 6_000), 0);
    assert!(!irq(&c, 6));
    // Sensing again while the pin is still low: latched at once, a new PORT event.
    w(&mut c, pin_cnf(P0, 11), 0xC | (3 << 16), 7_000);
    assert!(irq(&c, 6));
}

#[test]
fn clearing_latch_while_the_condition_holds_gives_a_new_edge() {
    let mut c = chip();
    w(&mut c, P0 + 0x524, 1, 0);
    w(&mut c, GPIOTE + 0x304, 1 << 31, 0);
    c.drive_input(Pin::new(0, 11), false, 0);
    w(&mut c, pin_cnf(P0, 11), 3 << 16, 10);
    assert!(irq(&c, 6));
    w(&mut c, GPIOTE + 0x17C, 0, 20);
    w(&mut c, P0 + 0x520, 1 << 11, 30);
    assert!(irq(&c, 6), "the LDETECT signal rose again");
}

#[test]
fn nfc_pads_cannot_drive_until_nfcpins_is_cleared_and_the_chip_reset() {
    let mut c = chip();
    w(&mut c, pin_cnf(P0, 9), 3, 0);
    w(&mut c, P0 + 0x508, 1 << 9, 0);
    assert!(
        c.outside().driven.is_empty(),
        "P0.09 is an NFC pad with UICR erased"
    );
    // embassy-nrf's nfc-pins-as-gpio: UICR.NFCPINS bit 0 cleared, then a reset.
    w(&mut c, 0x4001_E504, 1, 0);
    w(&mut c, 0x1000_120C, 0xFFFF_FFFE, 0);
    c.advance(50_000);
    assert_eq!(c.uicr_word(uicr::NFCPINS), 0xFFFF_FFFE);
    c.reset(ResetCause::Other);
    // Output::new: the level first, then the direction.
    w(&mut c, P0 + 0x508, 1 << 9, 60_000);
    w(&mut c, pin_cnf(P0, 9), 3, 60_000);
    assert_eq!(
        c.outside().driven,
        vec![(Pin::new(0, 9), Drive::High, 60_000)]
    );
}

#[test]
fn reset_releases_every_driven_pin() {
    let mut c = chip();
    w(&mut c, pin_cnf(P0, 15), 3, 0);
    w(&mut c, P0 + 0x508, 1 << 15, 0);
    c.advance(1_000);
    c.reset(ResetCause::Other);
    assert_eq!(
        c.outside().driven.last(),
        Some(&(Pin::new(0, 15), Drive::Released(Pull::None), 1_000))
    );
}

#[test]
fn gpiote_task_channel_drives_its_pin() {
    let mut c = chip();
    w(&mut c, GPIOTE + 0x510, 3 | (5 << 8) | (3 << 16), 0);
    assert_eq!(c.outside().driven, vec![(Pin::new(0, 5), Drive::Low, 0)]);
    w(&mut c, GPIOTE + 0x000, 1, 10);
    w(&mut c, GPIOTE + 0x060, 1, 20);
    assert_eq!(
        c.outside().driven[1..],
        [
            (Pin::new(0, 5), Drive::High, 10),
            (Pin::new(0, 5), Drive::Low, 20)
        ]
    );
}
