//! A register-level virtual Si4432 and a simulated RF medium (std), so radio code can be
//! tested on a PC through the same embedded-hal traits it uses on a board.
//!
//! Modelled after lora-rs' SX127x emulator: the chip is behavioural at
//! register level, interrupt semantics are exact, and nothing is imported from the driver
//! under test — register addresses and reset values here come from the datasheet, so a wrong
//! driver constant fails a test instead of being mirrored.
//!
//! # Using it in your tests
//! It is not on crates.io (`publish = false`): depend on it from your crate's tests by path
//! (or `git`) into a TauLink checkout, next to the driver you test:
//! ```toml
//! [dev-dependencies]
//! si4432-sim = { path = "../taulink/tests/si4432-sim" }
//! ```
//! It needs `std` and nothing of TauLink's: any Si4432 driver on embedded-hal 1.0 (blocking or
//! async) runs on it. The openlrs-ng crate's `guide` module has a complete host test of an
//! OpenLRSng link written against it.
//!
//! # What is modelled
//! - **Registers** ([`registers`]): datasheet reset values, read-only vs read-write, device
//!   type 0x08 / version 0x06 (B1), temperature ADC, battery level, AFC read-back.
//! - **FIFOs** ([`fifo`]): 64-byte TX and RX FIFOs, almost-full/almost-empty thresholds
//!   (0x7C–0x7E) as edge events, overflow/underflow → FIFO error interrupt, clear via 0x08.
//! - **Operating modes**: SDN shutdown, power-on reset (≈15 ms, then `ipor`), STANDBY,
//!   READY (crystal, 600 µs, then `ichiprdy`), TUNE, TX, RX with a 200 µs PLL settle;
//!   `swres`; automatic return to READY/TUNE after a packet is sent or a valid packet is
//!   received (unless 0x08 rxmpk); RX keeps searching after a CRC error.
//! - **Interrupts**: status 0x03/0x04 latch whether enabled or not, reading clears them;
//!   nIRQ is low while `(status & enable) != 0` and released only by reading the status;
//!   `irssi` when a frame pushes the in-band power to the 0x27 threshold.
//! - **Packet handler** ([`packet`]): preamble, sync word (1–4 bytes), header (0–4 bytes,
//!   check and enable masks, broadcast), fixed or variable length, CRC (CCITT, CRC-16,
//!   IEC-16, Biacheva; all or data only), PN9 whitening, packets longer than 64 bytes through
//!   the FIFO thresholds, RSSI (0x26) latched at sync.
//! - **Modem** ([`modem`]): carrier from 0x75–0x77 + hop channel × step + offset, TX bit
//!   rate (0x6E/0x6F/0x70), RX bit rate from clock recovery (0x1C, 0x21–0x23), deviation,
//!   IF bandwidth (approximate), AFC pull-in. A frame is received only if carrier, bit rate,
//!   deviation and modulation fit the receiver. Airtime follows from the configuration.
//! - **Medium** ([`Medium`]): positions → path loss → received power (TX power from 0x6D),
//!   noise floor and sensitivity by bit rate, bit errors from SINR (the CRC catches them),
//!   random loss, interference bursts, collisions (optional capture), and a trace of every
//!   frame with every receiver's outcome ([`TraceFrame`]). [`Medium::inject_packet`] plays
//!   a frame from an ideal transmitter in the receiver's own format (lora-rs' `inject_rx`).
//! - **Execution** ([`Simulation`]): the simulators' one deterministic single-threaded
//!   executor and virtual time (`sim-exec`), with the chips' events as stops of that time;
//!   all randomness from one seed ([`sim_rng::SplitMix64`]). A board's clock ([`SimClock`]:
//!   its epoch and crystal drift, from [`Simulation::time`]) is the same one the
//!   packet-level mock uses (with `telemetry`'s `std` feature it is the link's `LinkClock`).
//! - **The MCU's bus** (per radio, [`RadioConfig`]): every SPI transaction takes
//!   `spi_overhead_ns` + bytes × 8 / `spi_clock_hz` of virtual time before it acts on the
//!   chip (async: the task sleeps and others run, as with DMA; blocking: the whole world
//!   advances, a busy-wait). Defaults: [`SPI_CLOCK_F405_HZ`] (5.25 MHz, the flight board;
//!   [`SPI_CLOCK_NRF52840_HZ`] = 8 MHz for the module), [`SPI_OVERHEAD_NS`] = 3 µs. nIRQ
//!   reaches a waiting task `irq_latency_ns` ([`IRQ_LATENCY_NS`] = 5 µs) after its falling
//!   edge; a wait that starts with the line already low returns at once.
//!   [`RadioConfig::with_instant_bus`] turns both off (tests of the chip's own timing).
//!   [`ChipHandle::spi_stats`] counts transactions, failures and bus time.
//! - **Faults** ([`ChipHandle`], [`Fault`]): unplugged module (SPI reads all 0xFF or 0x00),
//!   nIRQ stuck low or stuck high (`Fault::NirqStuckLow` / `NirqStuckHigh`), SPI bus errors
//!   (the next N transactions, [`ChipHandle::fail_spi_transactions`], or each with a
//!   probability from the seed, [`ChipHandle::set_spi_error_rate`]: the transaction takes its
//!   time, reaches nothing and returns [`SpiError`]), power-on reset (brown-out) at any moment
//!   ([`ChipHandle::power_on_reset`]; at a given time: a task that sleeps until then and
//!   calls it), register corruption.
//!
//! # What is not
//! Direct (GPIO/SDI) modulation, OOK details, low-duty-cycle mode, wake-up timer, low-battery
//! detector, antenna diversity, auto-TX, GPIO pin functions (CCA output), the
//! invalid-preamble and external interrupts, `irssi` on interference bursts, and the exact IF filter table. The CRC seed
//! (0xFFFF) and the IEC-16 / Biacheva polynomials are this model's assumptions; both
//! simulated ends agree, but they are not checked against silicon. SPI transactions all cost
//! the same per byte (no clock stretching, no bus shared between devices).
//!
//! # Example
//! Two chips 100 m apart; one sends 5 bytes with raw register writes, the other receives.
//! ```
//! use core::time::Duration;
//! use embedded_hal::spi::{Operation, SpiDevice};
//! use si4432_sim::{RadioConfig, Simulation};
//!
//! fn write(spi: &mut impl SpiDevice, address: u8, data: &[u8]) {
//!     spi.transaction(&mut [Operation::Write(&[address | 0x80]), Operation::Write(data)]).unwrap();
//! }
//! fn read(spi: &mut impl SpiDevice, address: u8, buf: &mut [u8]) {
//!     spi.transaction(&mut [Operation::Write(&[address]), Operation::Read(buf)]).unwrap();
//! }
//!
//! let sim = Simulation::new(1);
//! let medium = sim.medium();
//! let mut a = medium.add_radio(RadioConfig::at([0.0, 0.0, 0.0]));
//! let mut b = medium.add_radio(RadioConfig::at([100.0, 0.0, 0.0]));
//! for spi in [&mut a.spi, &mut b.spi] {
//!     let mut status = [0u8; 2];
//!     read(spi, 0x03, &mut status); // clears ipor/ichiprdy left from power-up (nIRQ high)
//!     write(spi, 0x71, &[0x22]); // FSK from the FIFO (reset: unmodulated carrier)
//!     write(spi, 0x05, &[0x06]); // enpksent | enpkvalid
//! }
//! write(&mut b.spi, 0x07, &[0x05]); // RX on
//! write(&mut a.spi, 0x3E, &[5]); // packet length
//! write(&mut a.spi, 0x7F, b"hello");
//! write(&mut a.spi, 0x07, &[0x09]); // TX on
//!
//! assert!(sim.run_until_or(Duration::from_millis(10), || b.chip.nirq_is_low()));
//! let mut status = [0u8; 2];
//! read(&mut b.spi, 0x03, &mut status);
//! assert_eq!(status[0] & 0x02, 0x02); // ipkvalid
//! let mut payload = [0u8; 5];
//! read(&mut b.spi, 0x7F, &mut payload);
//! assert_eq!(&payload, b"hello");
//! assert!(!b.chip.nirq_is_low()); // released by reading 0x03/0x04
//! ```
//! In async code, spawn one task per radio end with [`Simulation::spawn`] and drive the
//! driver through `a.spi` (`embedded_hal_async::spi::SpiDevice`), `a.nirq`
//! (`embedded_hal_async::digital::Wait`) and `a.delay` (`embedded_hal_async::delay::DelayNs`).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod access;
mod acquire;
mod air;
mod chip;
mod executor;
pub mod fifo;
mod inject;
mod medium;
pub mod modem;
pub mod packet;
mod pins;
pub mod propagation;
pub mod registers;
mod rx;
mod trace;
mod tx;
mod world;

pub use chip::{ChipState, Fault, PLL_SETTLE_NS, POWER_ON_RESET_NS, XTAL_START_NS};
pub use executor::{Simulation, Spawner};
pub use medium::{
    ChipHandle, IRQ_LATENCY_NS, Interference, Medium, MediumConfig, RadioConfig, RadioHandle,
    SPI_CLOCK_F405_HZ, SPI_CLOCK_NRF52840_HZ, SPI_OVERHEAD_NS,
};
pub use pins::{SimDelay, SimIrq, SimSdn, SimSpi, SpiError};
pub use sim_exec::{SimClock, Sleep, Task, VirtualTime};
pub use trace::{Outcome, RadioId, Reception, TraceFrame};
pub use world::SpiStats;
