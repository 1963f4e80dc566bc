//! The chip clocked byte by byte between nSEL edges, as a board model does for an MCU's SPI
//! controller (`ChipHandle::select` / `clock_byte` / `deselect`), and the medium stepped from
//! outside the executor (`Medium::advance_to_ns`, `next_event_ns`) with nIRQ's edges kept
//! with their times.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

use si4432_sim::{ChipHandle, Fault, POWER_ON_RESET_NS, RadioConfig, Simulation, XTAL_START_NS};

/// A transaction of `bytes`, one byte at a time: what came back on MISO.
fn transaction(chip: &ChipHandle, bytes: &[u8]) -> Vec<Option<u8>> {
    chip.select();
    let miso = bytes.iter().map(|&b| chip.clock_byte(b)).collect();
    chip.deselect();
    miso
}

#[test]
fn one_transaction_per_select_address_first_then_data() {
    let sim = Simulation::new(1);
    let r = sim.medium().add_radio(RadioConfig::default());
    // Device type and version as a two-byte burst read: MISO carries nothing useful during
    // the address byte, then the registers.
    assert_eq!(
        transaction(&r.chip, &[0x00, 0, 0]),
        vec![Some(0x00), Some(0x08), Some(0x06)]
    );
    // A burst write from 0x36, then a read back in a new transaction.
    transaction(&r.chip, &[0x80 | 0x36, 1, 2, 3]);
    assert_eq!(
        transaction(&r.chip, &[0x36, 0, 0, 0]),
        vec![Some(0x00), Some(1), Some(2), Some(3)]
    );
    // Without nSEL low nothing drives MISO and a write reaches nothing.
    assert_eq!(r.chip.clock_byte(0x80 | 0x36), None);
    assert_eq!(r.chip.clock_byte(9), None);
    assert_eq!(r.chip.peek(0x36), 1);
    // A new select restarts the decoder: its first byte is an address again.
    r.chip.select();
    r.chip.clock_byte(0x80 | 0x37);
    r.chip.select();
    r.chip.clock_byte(0x38);
    assert_eq!(r.chip.clock_byte(0), Some(3));
    r.chip.deselect();
    assert_eq!(r.chip.peek(0x37), 2);
}

#[test]
fn reading_the_status_releases_nirq_and_the_edges_carry_their_times() {
    let sim = Simulation::new(1);
    let medium = sim.medium();
    let r = medium.add_radio(RadioConfig::default());
    r.chip.record_nirq_edges();
    // Powered with ipor/ichiprdy pending: nIRQ low from the start.
    assert!(r.chip.nirq_is_low());
    transaction(&r.chip, &[0x03, 0, 0]);
    assert!(!r.chip.nirq_is_low());
    assert_eq!(r.chip.take_nirq_edges(), vec![(0, false)]);
    // Enable ipor, then a software reset (0x07 swres): the chip raises ichiprdy only, so
    // enable that too and let the medium run from outside the executor.
    transaction(&r.chip, &[0x80 | 0x06, 0x02]); // enchiprdy
    transaction(&r.chip, &[0x80 | 0x07, 0x80]); // swres
    let due = medium.next_event_ns().unwrap();
    assert!(due > 0 && due <= XTAL_START_NS + POWER_ON_RESET_NS, "{due}");
    medium.advance_to_ns(10_000_000);
    let edges = r.chip.take_nirq_edges();
    assert_eq!(edges.len(), 1, "{edges:?}");
    let (t, low) = edges[0];
    assert!(low);
    assert_eq!(
        t, due,
        "the edge is stamped when the chip raised the interrupt"
    );
    assert_eq!(medium.now().as_nanos(), 10_000_000);
    // Time never runs back.
    medium.advance_to_ns(5);
    assert_eq!(medium.now().as_nanos(), 10_000_000);
    assert!(r.chip.take_nirq_edges().is_empty());
}

#[test]
fn an_injected_bus_error_keeps_a_whole_transaction_from_the_chip() {
    let sim = Simulation::new(1);
    let r = sim.medium().add_radio(RadioConfig::default());
    r.chip.fail_spi_transactions(1);
    assert_eq!(transaction(&r.chip, &[0x80 | 0x36, 0x55]), vec![None, None]);
    assert_eq!(r.chip.peek(0x36), 0x2D, "reset value (sync word 3) kept");
    transaction(&r.chip, &[0x80 | 0x36, 0x55]);
    assert_eq!(r.chip.peek(0x36), 0x55);
    let stats = r.chip.spi_stats();
    assert_eq!((stats.transactions, stats.failed), (2, 1));
    // An unplugged module answers its fault's MISO level.
    r.chip.set_fault(Fault::Unplugged { miso: 0xFF });
    assert_eq!(transaction(&r.chip, &[0x00, 0])[1], Some(0xFF));
}
