//! UICR through the NVMC (embassy-nrf's `uicr_write`), REGOUT0 at reset, NVMC timing and
//! the CPU stall, flash programming.

use m4_sim::Bus;
use m4_sim::bus::ResetCause;

use super::{chip, chip_with, r, w};
use crate::nrf52840::{Config, Supply, resetreas, uicr};

const NVMC_READY: u32 = 0x4001_E400;
const NVMC_CONFIG: u32 = 0x4001_E504;
const UICR_REGOUT0: u32 = 0x1000_1304;

#[test]
fn erased_uicr_on_vddh_gives_1v8_gpio() {
    let c = chip();
    assert_eq!(c.uicr_word(uicr::REGOUT0), 0xFFFF_FFFF);
    assert_eq!(c.gpio_supply_volts(), 1.8);
}

#[test]
fn vdd_supplied_gpio_follows_vdd() {
    let c = chip_with(Config {
        supply: Supply::Vdd { volts: 3.0 },
        ..Config::default()
    });
    assert_eq!(c.gpio_supply_volts(), 3.0);
}

#[test]
fn regout0_written_by_the_nvmc_applies_at_the_next_reset() {
    let mut c = chip();
    let t = 1_000;
    // embassy-nrf uicr_write: CONFIG = Wen, wait READY, store, wait READY, CONFIG = Ren.
    w(&mut c, NVMC_CONFIG, 1, t);
    assert_eq!(r(&mut c, NVMC_READY, t), 1);
    w(&mut c, UICR_REGOUT0, 0xFFFF_FFFD, t);
    assert_eq!(
        r(&mut c, NVMC_READY, t + 40_999),
        0,
        "a word write takes 41 µs"
    );
    assert_eq!(r(&mut c, NVMC_READY, t + 41_000), 1);
    w(&mut c, NVMC_CONFIG, 0, t + 41_000);
    assert_eq!(r(&mut c, UICR_REGOUT0, t + 41_000), 0xFFFF_FFFD);
    assert_eq!(c.gpio_supply_volts(), 1.8, "REGOUT0 is read at reset");
    c.reset(ResetCause::Other);
    assert_eq!(c.gpio_supply_volts(), 3.3);
    assert_eq!(c.reset_reason(), resetreas::SREQ);
}

#[test]
fn uicr_store_without_wen_is_refused_and_noted() {
    let mut c = chip();
    w(&mut c, UICR_REGOUT0, 0xFFFF_FFFD, 10);
    assert_eq!(c.uicr_word(uicr::REGOUT0), 0xFFFF_FFFF);
    assert!(c.records().notes().iter().any(|n| n.block == "NVMC"));
}

#[test]
fn page_erase_takes_85_ms_and_stalls_fetches_from_flash_once() {
    let mut c = chip();
    c.load_segment(0xEC000, &[0, 1, 2, 3]).unwrap();
    let gen0 = c.code_generation();
    w(&mut c, NVMC_CONFIG, 2, 0);
    w(&mut c, 0x4001_E508, 0xEC000, 0);
    assert_eq!(c.flash()[0xEC000..0xEC004], [0xFF; 4]);
    assert!(c.code_generation() > gen0);
    // 85 ms at 64 MHz, reported once; RAM code is not held up.
    assert_eq!(c.fetch_stall(0x2000_0000, true), 0);
    assert_eq!(c.fetch_stall(0x100, false), 1 + 5_440_000);
    assert_eq!(c.fetch_stall(0x104, true), 0);
    assert_eq!(r(&mut c, NVMC_READY, 84_999_999), 0);
    assert_eq!(r(&mut c, NVMC_READY, 85_000_000), 1);
}

#[test]
fn flash_word_program_only_clears_bits() {
    let mut c = chip();
    w(&mut c, NVMC_CONFIG, 1, 0);
    w(&mut c, 0xEC000, 0x1234_5678, 0);
    w(&mut c, 0xEC000, 0xFFFF_0000, 100_000);
    assert_eq!(r(&mut c, 0xEC000, 200_000), 0x1234_0000);
}

#[test]
fn eraseuicr_restores_the_erased_page() {
    let mut c = chip();
    c.program_uicr(uicr::REGOUT0, 0xFFFF_FFFD);
    assert_eq!(c.gpio_supply_volts(), 3.3, "programmed before power-up");
    w(&mut c, NVMC_CONFIG, 2, 0);
    w(&mut c, 0x4001_E514, 1, 0);
    assert_eq!(c.uicr_word(uicr::REGOUT0), 0xFFFF_FFFF);
    c.reset(ResetCause::Other);
    assert_eq!(c.gpio_supply_volts(), 1.8);
}

#[test]
fn icache_hits_cost_nothing_misses_the_wait_state() {
    let mut c = chip();
    // Cache off (reset value): every line change waits.
    assert_eq!(c.fetch_stall(0x1000, false), 1);
    assert_eq!(c.fetch_stall(0x1002, true), 0);
    assert_eq!(c.fetch_stall(0x2000, false), 1);
    assert_eq!(c.fetch_stall(0x1000, false), 1);
    // ICACHECNF.CACHEEN with profiling: the second visit of a line hits.
    w(&mut c, 0x4001_E540, 0x101, 0);
    assert_eq!(c.fetch_stall(0x3000, false), 1);
    assert_eq!(c.fetch_stall(0x4000, false), 1);
    assert_eq!(c.fetch_stall(0x3000, false), 0);
    assert_eq!(r(&mut c, 0x4001_E548, 0), 1, "IHIT");
    assert_eq!(r(&mut c, 0x4001_E54C, 0), 2, "IMISS");
}

#[test]
fn a_store_into_ram_code_changes_the_code_generation() {
    use m4_sim::Width;
    let mut c = chip();
    assert!(c.fetch(0x2000_1000).is_some());
    let g = c.code_generation();
    c.write(0x2000_2000, Width::Word, 1, 0).unwrap();
    assert_eq!(c.code_generation(), g, "data page");
    c.write(0x2000_1004, Width::Word, 1, 0).unwrap();
    assert_eq!(c.code_generation(), g + 1, "a page code ran from");
    // The code-bus alias of RAM fetches the same bytes.
    assert_eq!(c.fetch(0x0080_1004), Some(1));
}
