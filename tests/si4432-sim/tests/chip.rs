//! One chip on its own: reset values, register access, interrupt latching and nIRQ, mode
//! settle times, software and power-on reset, faults. Raw register sequences only.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

mod common;

use common::*;
use core::time::Duration;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::spi::{Operation, SpiDevice};
use si4432_sim::{ChipState, Fault, RadioConfig, RadioHandle, Simulation};

/// One chip on an ideal bus: these tests time the chip itself to the nanosecond.
fn one() -> (Simulation, RadioHandle) {
    let sim = Simulation::new(1);
    let radio = sim
        .medium()
        .add_radio(RadioConfig::default().with_instant_bus());
    (sim, radio)
}

#[test]
fn datasheet_reset_values_read_back_over_spi() {
    let (_sim, mut r) = one();
    assert_eq!(
        read_n(&mut r.spi, 0x00, 2),
        vec![0x08, 0x06],
        "device type EZRadioPRO, version B1"
    );
    assert_eq!(read(&mut r.spi, 0x05), 0x00);
    assert_eq!(read(&mut r.spi, 0x06), 0x03);
    assert_eq!(read(&mut r.spi, 0x07), 0x01);
    assert_eq!(read(&mut r.spi, 0x09), 0x7F);
    assert_eq!(read(&mut r.spi, 0x0C), 0x00);
    assert_eq!(read_n(&mut r.spi, 0x1C, 2), vec![0x01, 0x40]);
    assert_eq!(read_n(&mut r.spi, 0x30, 1), vec![0x8D]);
    assert_eq!(
        read_n(&mut r.spi, 0x32, 6),
        vec![0x0C, 0x22, 0x08, 0x2A, 0x2D, 0xD4]
    );
    assert_eq!(read_n(&mut r.spi, 0x43, 4), vec![0xFF; 4]);
    assert_eq!(
        read_n(&mut r.spi, 0x6D, 6),
        vec![0x18, 0x0A, 0x3D, 0x0C, 0x00, 0x20]
    );
    assert_eq!(read_n(&mut r.spi, 0x75, 3), vec![0x75, 0xBB, 0x80]);
    assert_eq!(read_n(&mut r.spi, 0x7C, 3), vec![0x37, 0x04, 0x37]);
    let modem = r.chip.modem().unwrap();
    assert_eq!(modem.carrier_hz, 915e6);
}

#[test]
fn read_only_registers_ignore_writes_and_bursts_increment() {
    let (_sim, mut r) = one();
    write(&mut r.spi, 0x00, &[0xFF, 0xFF]);
    assert_eq!(read_n(&mut r.spi, 0x00, 2), vec![0x08, 0x06]);
    // A burst write from 0x36 fills 0x36..0x39.
    write(&mut r.spi, 0x36, &[1, 2, 3, 4]);
    assert_eq!(read_n(&mut r.spi, 0x36, 4), vec![1, 2, 3, 4]);
    // A single transfer: address byte, then data in the same buffer.
    let mut buf = [0x75, 0, 0, 0];
    r.spi
        .transaction(&mut [Operation::TransferInPlace(&mut buf)])
        .unwrap();
    assert_eq!(buf, [0x00, 0x75, 0xBB, 0x80]);
}

#[test]
fn interrupt_status_is_read_to_clear_and_nirq_follows_enabled_bits() {
    let (_sim, mut r) = one();
    // Powered up: ipor and ichiprdy latched, both enabled by default (0x06 = 0x03).
    assert!(r.nirq.is_low().unwrap());
    assert_eq!(r.chip.peek(0x04), 0x03);
    // Reading 0x03 alone leaves status 2 pending: nIRQ stays low.
    assert_eq!(read(&mut r.spi, 0x03), 0x00);
    assert!(r.nirq.is_low().unwrap());
    // Reading 0x04 returns and clears both bits, releasing nIRQ.
    assert_eq!(read(&mut r.spi, 0x04), 0x03);
    assert!(r.nirq.is_high().unwrap());
    assert_eq!(read(&mut r.spi, 0x04), 0x00);

    // Disabled sources still latch, but do not pull nIRQ low until enabled.
    write(&mut r.spi, 0x06, &[0x00]);
    write(&mut r.spi, 0x07, &[0x80]); // swres
    r.delay.delay_us(700);
    write(&mut r.spi, 0x06, &[0x00]);
    assert_eq!(r.chip.peek(0x04), 0x02, "ichiprdy latched after swres");
    assert!(r.nirq.is_high().unwrap());
    write(&mut r.spi, 0x06, &[0x02]);
    assert!(r.nirq.is_low().unwrap());
    assert_eq!(status(&mut r.spi), (0x00, 0x02));
    assert!(r.nirq.is_high().unwrap());
}

#[test]
fn software_reset_restores_defaults_and_raises_chip_ready_after_the_crystal_starts() {
    let (sim, mut r) = one();
    status(&mut r.spi);
    write(&mut r.spi, 0x75, &[0x53, 0x00, 0x00]);
    write(&mut r.spi, 0x07, &[0x80]);
    assert_eq!(read_n(&mut r.spi, 0x75, 3), vec![0x75, 0xBB, 0x80]);
    assert!(r.nirq.is_high().unwrap());
    let t0 = sim.now();
    r.delay.delay_us(599);
    assert!(r.nirq.is_high().unwrap());
    r.delay.delay_us(1);
    assert!(r.nirq.is_low().unwrap());
    assert_eq!(sim.now() - t0, Duration::from_micros(600));
    assert_eq!(
        status(&mut r.spi),
        (0x00, 0x02),
        "ichiprdy only: swres is not a POR"
    );
}

#[test]
fn sdn_shutdown_and_power_on_reset_sequence() {
    let (_sim, mut r) = one();
    status(&mut r.spi);
    write(&mut r.spi, 0x0C, &[0xD5]);
    r.sdn.set_high().unwrap();
    assert_eq!(r.chip.state(), ChipState::Shutdown);
    assert_eq!(read(&mut r.spi, 0x00), 0x00, "no answer in shutdown");
    assert!(r.nirq.is_high().unwrap());
    r.delay.delay_ms(50);
    r.sdn.set_low().unwrap();
    assert_eq!(r.chip.state(), ChipState::PowerOnReset);
    r.delay.delay_us(14_999);
    assert_eq!(read(&mut r.spi, 0x00), 0x00, "still in POR");
    r.delay.delay_us(1);
    assert_eq!(read(&mut r.spi, 0x00), 0x08);
    assert_eq!(status(&mut r.spi), (0x00, 0x01), "ipor first");
    r.delay.delay_us(600);
    assert_eq!(status(&mut r.spi), (0x00, 0x02), "then ichiprdy");
    assert_eq!(
        read(&mut r.spi, 0x0C),
        0x00,
        "registers lost: the 'locked module' check fires"
    );
    assert_eq!(r.chip.state(), ChipState::Ready);
}

#[test]
fn operating_mode_settle_times() {
    let (sim, mut r) = one();
    configure_57600(&mut r.spi, true);
    // READY → RX: 200 µs PLL settle; device status cps = 01 once in RX.
    write(&mut r.spi, 0x07, &[0x05]);
    assert_eq!(r.chip.state(), ChipState::SettlingRx);
    assert_eq!(read(&mut r.spi, 0x02) & 0x03, 0x00);
    r.delay.delay_us(199);
    assert_eq!(r.chip.state(), ChipState::SettlingRx);
    r.delay.delay_us(1);
    assert_eq!(r.chip.state(), ChipState::Rx);
    assert_eq!(read(&mut r.spi, 0x02) & 0x03, 0x01);
    assert_eq!(read(&mut r.spi, 0x31) & 0x20, 0x20, "EzMAC pksrch");
    // STANDBY (crystal off) → RX: crystal 600 µs + PLL 200 µs.
    write(&mut r.spi, 0x07, &[0x00]);
    assert_eq!(r.chip.state(), ChipState::Standby);
    let t0 = sim.now();
    write(&mut r.spi, 0x07, &[0x04]);
    r.delay.delay_us(799);
    assert_eq!(r.chip.state(), ChipState::SettlingRx);
    r.delay.delay_us(1);
    assert_eq!(r.chip.state(), ChipState::Rx);
    assert_eq!(sim.now() - t0, Duration::from_micros(800));
    // TUNE, READY.
    write(&mut r.spi, 0x07, &[0x02]);
    assert_eq!(r.chip.state(), ChipState::Tune);
    write(&mut r.spi, 0x07, &[0x01]);
    assert_eq!(r.chip.state(), ChipState::Ready);
}

#[test]
fn unplugged_module_reads_all_ones_or_all_zeros() {
    let (_sim, mut r) = one();
    r.chip.set_fault(Fault::Unplugged { miso: 0xFF });
    assert_eq!(read_n(&mut r.spi, 0x00, 2), vec![0xFF, 0xFF]);
    assert!(r.nirq.is_high().unwrap());
    write(&mut r.spi, 0x09, &[0x10]);
    r.chip.set_fault(Fault::Unplugged { miso: 0x00 });
    assert_eq!(read_n(&mut r.spi, 0x00, 2), vec![0x00, 0x00]);
    r.chip.set_fault(Fault::None);
    assert_eq!(read(&mut r.spi, 0x00), 0x08);
    assert_eq!(
        read(&mut r.spi, 0x09),
        0x7F,
        "writes while unplugged went nowhere"
    );
}

#[test]
fn injected_power_on_reset_and_register_corruption() {
    let (_sim, mut r) = one();
    configure_57600(&mut r.spi, true);
    start_rx(&mut r.spi);
    r.delay.delay_us(300);
    assert_eq!(r.chip.state(), ChipState::Rx);
    r.chip.power_on_reset();
    assert_eq!(r.chip.state(), ChipState::PowerOnReset);
    r.delay.delay_ms(16);
    assert_eq!(status(&mut r.spi), (0x00, 0x03));
    assert_eq!(read(&mut r.spi, 0x75), 0x75, "configuration lost");
    assert_eq!(read(&mut r.spi, 0x07), 0x01);

    r.chip.poke(0x75, 0x40);
    assert_eq!(read(&mut r.spi, 0x75), 0x40);
    // fb = 0, hbsel = 0, fc = 0xBB80: (24 + 0.75) · 10 MHz.
    assert_eq!(r.chip.modem().unwrap().carrier_hz, 247.5e6);
}

#[test]
fn temperature_and_battery_readings() {
    let sim = Simulation::new(1);
    let config = RadioConfig {
        temperature_c: 25.0,
        supply_v: 3.0,
        ..RadioConfig::default()
    };
    let mut r = sim.medium().add_radio(config);
    write(&mut r.spi, 0x12, &[0x20]);
    write(&mut r.spi, 0x0F, &[0x80]);
    assert_eq!(read(&mut r.spi, 0x0F) & 0x80, 0x80, "adcdone");
    // −64…64 °C range, 0.5 °C per LSB: (25 + 64) · 2 = 178.
    assert_eq!(read(&mut r.spi, 0x11), 178);
    // vbat[4:0]: 1.7 V + 50 mV · 26 = 3.0 V; the 5-bit field saturates at 3.25 V.
    assert_eq!(read(&mut r.spi, 0x1B), 26);
    let high = RadioConfig {
        supply_v: 3.3,
        ..RadioConfig::default()
    };
    let mut r = sim.medium().add_radio(high);
    assert_eq!(read(&mut r.spi, 0x1B), 31);
}
