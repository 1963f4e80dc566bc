//! SPIM3 at 8 MHz as the radio uses it (Spim::new + a transfer, embassy-nrf's
//! `prepare_dma_transfer`), EasyDMA limits, and anomaly 198's conditions and workaround.

use m4_sim::{Bus, Width};

use super::{chip, chip_with, irq, r, run_to, w};
use crate::nrf52840::{Anomaly198Mode, Config, Master};

const SPIM3: u32 = 0x4002_F000;
const TX: u32 = 0x2000_2000;
const RX: u32 = 0x2000_2100;

/// Spim::new(SPI3, sck P0.17, miso P0.22, mosi P0.20, 8 MHz, mode 0).
fn setup(c: &mut super::Chip, t: u64) {
    w(c, SPIM3 + 0x508, 17, t);
    w(c, SPIM3 + 0x50C, 20, t);
    w(c, SPIM3 + 0x510, 22, t);
    w(c, SPIM3 + 0x500, 7, t);
    w(c, SPIM3 + 0x524, 0x8000_0000, t);
    w(c, SPIM3 + 0x554, 0, t);
    w(c, SPIM3 + 0x5C0, 0, t);
    w(c, SPIM3 + 0x308, 0xFFFF_FFFF, t);
}

fn transfer(c: &mut super::Chip, tx_len: u32, rx_len: u32, t: u64) {
    w(c, SPIM3 + 0x534, RX, t);
    w(c, SPIM3 + 0x538, rx_len, t);
    w(c, SPIM3 + 0x544, TX, t);
    w(c, SPIM3 + 0x548, tx_len, t);
    w(c, SPIM3 + 0x118, 0, t);
    w(c, SPIM3 + 0x304, 1 << 6, t);
    w(c, SPIM3 + 0x010, 1, t);
}

#[test]
fn bytes_go_to_the_board_one_microsecond_apart_and_end_raises_irq_47() {
    let mut c = chip();
    setup(&mut c, 0);
    c.write(TX, Width::Word, 0x0000_7F02, 0).unwrap(); // read register 0x02... as 2 bytes
    c.outside_mut().miso.extend([0x00, 0x08]);
    transfer(&mut c, 2, 2, 10_000);
    assert_eq!(r(&mut c, SPIM3 + 0x14C, 10_000), 1, "STARTED");
    run_to(&mut c, 12_000);
    assert_eq!(c.outside().spi, vec![(4, 0x02, 11_000), (4, 0x7F, 12_000)]);
    assert!(irq(&c, 47), "END on IRQ 47 = SPIM3");
    assert_eq!(c.ram()[0x2100..0x2102], [0x00, 0x08]);
    assert_eq!(r(&mut c, SPIM3 + 0x53C, 12_000), 2, "RXD.AMOUNT");
    assert_eq!(r(&mut c, SPIM3 + 0x120, 12_000), 1, "ENDTX");
}

#[test]
fn orc_fills_past_the_tx_buffer() {
    let mut c = chip();
    setup(&mut c, 0);
    w(&mut c, SPIM3 + 0x5C0, 0xA5, 0);
    c.write(TX, Width::Byte, 0x80, 0).unwrap();
    transfer(&mut c, 1, 3, 0);
    run_to(&mut c, 3_000);
    let mosi: Vec<u8> = c.outside().spi.iter().map(|s| s.1).collect();
    assert_eq!(mosi, [0x80, 0xA5, 0xA5]);
}

#[test]
fn a_flash_pointer_is_a_dma_fault() {
    let mut c = chip();
    setup(&mut c, 0);
    w(&mut c, SPIM3 + 0x544, 0x0000_1000, 0);
    w(&mut c, SPIM3 + 0x548, 4, 0);
    w(&mut c, SPIM3 + 0x010, 1, 0);
    assert_eq!(c.records().dma_faults()[0].channel, "SPIM3 TXD");
    assert_eq!(c.records().dma_faults()[0].addr, 0x1000);
}

#[test]
fn cpu_access_to_the_tx_buffers_ram_block_meets_anomaly_198() {
    let mut c = chip();
    setup(&mut c, 0);
    transfer(&mut c, 4, 4, 0);
    // The CPU reads a word in the same 8 KiB block (AHB slave 1) mid-transfer...
    c.read(0x2000_3FF0, Width::Word, 1_500).unwrap();
    // ...and one in another block, which is fine.
    c.read(0x2000_4000, Width::Word, 1_600).unwrap();
    run_to(&mut c, 5_000);
    let a = c.anomaly_198();
    assert_eq!((a.transfers, a.count), (1, 1));
    assert_eq!(a.hits[0].master, Master::Cpu);
    assert_eq!((a.hits[0].addr, a.hits[0].slave), (0x2000_3FF0, 1));
    // After END, no transfer: no condition.
    c.read(0x2000_3FF0, Width::Word, 6_000).unwrap();
    assert_eq!(c.anomaly_198().count, 1);
}

#[test]
fn the_workaround_register_covers_all_but_cpu_writes_into_the_buffer() {
    let mut c = chip();
    setup(&mut c, 0);
    // nrfx anomaly_198_enable: the TX buffer's block mask into 0x4000_0E00.
    w(&mut c, 0x4000_0E00, 1 << 1, 0);
    transfer(&mut c, 4, 4, 0);
    c.read(0x2000_3FF0, Width::Word, 1_500).unwrap();
    assert_eq!(c.anomaly_198().count, 0);
    c.write(TX + 2, Width::Byte, 0x55, 1_600).unwrap();
    assert_eq!(c.anomaly_198().count, 1);
}

#[test]
fn corrupt_mode_sends_zero_for_the_byte_on_the_wire() {
    let mut c = chip_with(Config {
        anomaly_198: Anomaly198Mode::Corrupt,
        ..Config::default()
    });
    setup(&mut c, 0);
    c.write(TX, Width::Word, 0x4433_2211, 0).unwrap();
    transfer(&mut c, 4, 0, 10_000);
    c.read(TX + 0x100, Width::Word, 11_500).unwrap(); // during byte 1
    run_to(&mut c, 15_000);
    let mosi: Vec<u8> = c.outside().spi.iter().map(|s| s.1).collect();
    assert_eq!(mosi, [0x11, 0x00, 0x33, 0x44]);
    assert_eq!(c.anomaly_198().corrupted_bytes, 1);
}

#[test]
fn uarte_easydma_counts_as_another_master() {
    let mut c = chip();
    setup(&mut c, 0);
    // UARTE1 receiving into the same block as SPIM3's TX buffer.
    w(&mut c, 0x4002_8524, 0x01D6_0000, 0);
    w(&mut c, 0x4002_8514, 32 + 13, 0);
    w(&mut c, 0x4002_8500, 8, 0);
    w(&mut c, 0x4002_8534, 0x2000_2200, 0);
    w(&mut c, 0x4002_8538, 8, 0);
    w(&mut c, 0x4002_8000, 1, 0);
    c.uart_receive(2, 0x41, 1_500);
    transfer(&mut c, 4, 0, 1_000);
    run_to(&mut c, 6_000);
    assert_eq!(c.anomaly_198().hits[0].master, Master::Dma("UARTE1 RXD"));
}
