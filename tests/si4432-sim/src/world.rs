//! The shared simulation state behind every handle: chips, air, and the virtual time
//! (`sim_exec::VirtualTime`) they and the tasks share.
//!
//! Time only moves forward through `VirtualTime::advance_one`/`advance_to` (the executor's
//! steps, or a busy-wait's `World::advance_to`), which process every chip event up to the
//! new time in time order (ties in radio order) before the wake-ups of that instant fire, so
//! when an SPI access or a task runs, every chip is exactly at `now`. An SPI transaction
//! costs its bus time first (`spi_cost_ns`, spent by the caller in `pins`), then acts on the
//! chip at once.

use core::task::Waker;
use std::collections::HashMap;

use embedded_hal::spi::Operation;

use crate::air::Air;
use crate::chip::{Chip, Ctx, Fault};
use crate::medium::{MediumConfig, RadioConfig};
use crate::propagation::path_loss_db;
use sim_exec::{Events, VirtualTime};
use sim_rng::SplitMix64;

/// Safety net: more chip steps than this at one instant means a model bug; stop, don't hang.
const MAX_STEPS_PER_INSTANT: usize = 1_000_000;

/// The nIRQ line of one radio and the tasks waiting on it.
#[derive(Debug, Default)]
pub(crate) struct IrqLine {
    pub low: bool,
    pub falling_edges: u64,
    pub rising_edges: u64,
    /// When the line last fell (for the interrupt latency).
    pub fell_at_ns: u64,
    pub waiters: Vec<Waker>,
    /// Every change (time ns, low) since the board last took them, when a board asked for
    /// them (`ChipHandle::record_nirq_edges`); `None`: not kept.
    pub edges: Option<Vec<(u64, bool)>>,
}

/// SPI bus statistics of one radio.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpiStats {
    /// Transactions started.
    pub transactions: u64,
    /// Transactions that failed (injected bus errors).
    pub failed: u64,
    /// Virtual time the bus was busy, ns.
    pub busy_ns: u64,
}

/// Injected SPI faults and statistics of one radio's bus.
#[derive(Debug, Default)]
pub(crate) struct SpiBus {
    pub fail_next: u32,
    pub error_rate: f64,
    pub stats: SpiStats,
}

#[derive(Debug)]
pub(crate) struct Radio {
    pub chip: Chip,
    pub config: RadioConfig,
    pub irq: IrqLine,
    pub spi: SpiBus,
    /// The byte-wise transaction in progress (nSEL low, `ChipHandle::select`).
    pub selected: Option<Selected>,
}

/// A transaction clocked byte by byte by a board's SPI controller.
#[derive(Debug, Default)]
pub(crate) struct Selected {
    session: Session,
    /// An injected bus error: nothing of it reaches the chip.
    failed: bool,
}

#[derive(Debug)]
pub(crate) struct World {
    pub time: VirtualTime,
    pub rng: SplitMix64,
    pub radios: Vec<Radio>,
    pub air: Air,
    pub attenuation_db: HashMap<(usize, usize), f64>,
}

/// The chips' events move the executor's time like its wake-ups do.
impl Events for World {
    fn next_due_ns(&self) -> Option<u64> {
        self.next_chip_event_ns()
    }

    fn process_due(&mut self) {
        World::process_due(self);
    }
}

/// Decoder state of one SPI transaction (nSEL low): the first byte is the address.
#[derive(Debug, Default)]
struct Session {
    address: Option<u8>,
    write: bool,
}

impl World {
    pub fn new(seed: u64, config: MediumConfig, time: VirtualTime) -> Self {
        Self {
            time,
            rng: SplitMix64::new(seed),
            radios: Vec::new(),
            air: Air::new(config),
            attenuation_db: HashMap::new(),
        }
    }

    pub fn add_radio(&mut self, config: RadioConfig) -> usize {
        let me = self.radios.len();
        let chip = Chip::new(me, config.physical());
        let low = chip.nirq_low();
        self.radios.push(Radio {
            chip,
            config,
            irq: IrqLine {
                low,
                ..IrqLine::default()
            },
            spi: SpiBus::default(),
            selected: None,
        });
        me
    }

    /// Current virtual time, ns.
    pub fn now_ns(&self) -> u64 {
        self.time.now_ns()
    }

    /// Earliest pending chip event.
    pub fn next_chip_event_ns(&self) -> Option<u64> {
        self.radios
            .iter()
            .filter_map(|r| r.chip.next_event_ns())
            .min()
    }

    /// Process every chip event and wake-up up to `t` in time order (a busy-wait: no task
    /// runs), then stand at `t`.
    pub fn advance_to(&mut self, t: u64) {
        let time = self.time.clone();
        time.advance_to(t, self);
    }

    /// Wake `waker` when virtual time reaches `deadline_ns`.
    pub fn add_timer(&mut self, deadline_ns: u64, waker: Waker) {
        self.time.wake_at_ns(deadline_ns, waker);
    }

    /// Run every chip step due at `now`, in radio order, until none is left.
    pub fn process_due(&mut self) {
        let now = self.now_ns();
        let mut steps = 0;
        loop {
            let mut progressed = false;
            for i in 0..self.radios.len() {
                while self
                    .radios
                    .get(i)
                    .and_then(|r| r.chip.next_event_ns())
                    .is_some_and(|t| t <= now)
                {
                    steps += 1;
                    if steps > MAX_STEPS_PER_INSTANT {
                        return;
                    }
                    progressed = true;
                    let started = self.with_chip(i, |chip, now, ctx| chip.process(now, ctx));
                    if let Some(Some(id)) = started {
                        self.on_transmission_start(i, id);
                    }
                    self.update_irq(i);
                }
            }
            if !progressed {
                return;
            }
        }
    }

    /// Run `f` on chip `i` with a context borrowing the rest of the world.
    pub fn with_chip<R>(
        &mut self,
        i: usize,
        f: impl FnOnce(&mut Chip, u64, &mut Ctx<'_>) -> R,
    ) -> Option<R> {
        let radio_count = self.radios.len();
        let now = self.now_ns();
        let Self {
            radios, air, rng, ..
        } = self;
        let radio = radios.get_mut(i)?;
        let mut ctx = Ctx {
            air,
            rng,
            radio_count,
        };
        Some(f(&mut radio.chip, now, &mut ctx))
    }

    /// A frame went on air at radio `from`: fill in its power at every radio and let every
    /// other radio decide whether it hears it.
    fn on_transmission_start(&mut self, from: usize, id: u64) {
        let Some((carrier_hz, tx_power_dbm)) = self
            .air
            .get(id)
            .map(|tx| (tx.carrier_hz, tx.modem.tx_power_dbm))
        else {
            return;
        };
        let powers: Vec<f64> = (0..self.radios.len())
            .map(|to| self.link_power_dbm(from, to, carrier_hz, tx_power_dbm))
            .collect();
        self.air.set_powers(id, powers);
        for to in (0..self.radios.len()).filter(|&to| to != from) {
            self.with_chip(to, |chip, now, ctx| {
                chip.consider(id, now, ctx);
                chip.check_rssi_threshold(now, ctx);
            });
            self.update_irq(to);
        }
    }

    /// Power arriving at radio `to` from radio `from` transmitting `tx_power_dbm` on `carrier_hz`.
    pub fn link_power_dbm(
        &self,
        from: usize,
        to: usize,
        carrier_hz: f64,
        tx_power_dbm: f64,
    ) -> f64 {
        let (Some(a), Some(b)) = (self.radios.get(from), self.radios.get(to)) else {
            return -200.0;
        };
        let [ax, ay, az] = a.config.position_m;
        let [bx, by, bz] = b.config.position_m;
        let distance_m = ((ax - bx).powi(2) + (ay - by).powi(2) + (az - bz).powi(2)).sqrt();
        let key = (from.min(to), from.max(to));
        let extra_db = self.attenuation_db.get(&key).copied().unwrap_or(0.0);
        tx_power_dbm + a.config.antenna_gain_dbi + b.config.antenna_gain_dbi
            - path_loss_db(distance_m, carrier_hz, self.air.config.path_loss_exponent)
            - extra_db
    }

    /// Re-evaluate nIRQ of radio `i`; wake its waiters on any change.
    pub fn update_irq(&mut self, i: usize) {
        let now = self.now_ns();
        let Some(radio) = self.radios.get_mut(i) else {
            return;
        };
        let low = radio.chip.nirq_low();
        if low != radio.irq.low {
            radio.irq.low = low;
            if low {
                radio.irq.falling_edges += 1;
                radio.irq.fell_at_ns = now;
            } else {
                radio.irq.rising_edges += 1;
            }
            if let Some(edges) = radio.irq.edges.as_mut() {
                edges.push((now, low));
            }
            for waker in radio.irq.waiters.drain(..) {
                waker.wake();
            }
        }
    }

    /// What the RSSI register of radio `i` would read now if nothing were latched.
    fn live_rssi(&self, i: usize) -> u8 {
        self.radios
            .get(i)
            .map_or(0, |r| r.chip.live_rssi(&self.air, self.now_ns()))
    }

    /// Bus time of `operations` on radio `i`: bytes × 8 at its SPI clock plus the
    /// per-transaction overhead (`DelayNs` operations are spent inside [`World::spi`]).
    pub fn spi_cost_ns(&self, i: usize, operations: &[Operation<'_, u8>]) -> u64 {
        let Some(config) = self.radios.get(i).map(|r| r.config) else {
            return 0;
        };
        if config.spi_clock_hz == 0 {
            return 0;
        }
        let bytes: usize = operations
            .iter()
            .map(|op| match op {
                Operation::Read(b) => b.len(),
                Operation::Write(b) => b.len(),
                Operation::Transfer(r, w) => r.len().max(w.len()),
                Operation::TransferInPlace(b) => b.len(),
                Operation::DelayNs(_) => 0,
            })
            .sum();
        let bits = bytes as u64 * 8;
        config.spi_overhead_ns + (bits * 1_000_000_000).div_ceil(u64::from(config.spi_clock_hz))
    }

    /// nSEL of radio `i` falls: a byte-wise transaction starts (an injected bus error
    /// decides now whether it reaches the chip). A select while selected starts over.
    pub fn select(&mut self, i: usize) {
        self.process_due();
        let Some(radio) = self.radios.get_mut(i) else {
            return;
        };
        radio.spi.stats.transactions += 1;
        let bus = &mut radio.spi;
        let failed = if bus.fail_next > 0 {
            bus.fail_next -= 1;
            true
        } else {
            bus.error_rate > 0.0 && self.rng.chance(bus.error_rate)
        };
        if let Some(r) = self.radios.get_mut(i) {
            if failed {
                r.spi.stats.failed += 1;
            }
            r.selected = Some(Selected {
                session: Session::default(),
                failed,
            });
        }
    }

    /// One byte of the selected transaction of radio `i`: MOSI in, MISO out. `None` when
    /// nothing drives MISO: nSEL high (the chip's SDO is tri-stated), or a transaction an
    /// injected bus error kept from the chip.
    pub fn clock_byte(&mut self, i: usize, mosi: u8) -> Option<u8> {
        self.process_due();
        let mut selected = self.radios.get_mut(i).and_then(|r| r.selected.take())?;
        let miso = (!selected.failed).then(|| self.spi_byte(i, &mut selected.session, mosi));
        if let Some(r) = self.radios.get_mut(i) {
            r.selected = Some(selected);
        }
        self.process_due();
        self.update_irq(i);
        miso
    }

    /// nSEL of radio `i` rises: the transaction ends.
    pub fn deselect(&mut self, i: usize) {
        if let Some(r) = self.radios.get_mut(i) {
            r.selected = None;
        }
    }

    /// One SPI transaction on radio `i` whose bus time (`cost_ns`) has been spent: fails if
    /// a bus error was injected (nothing reaches the chip), else acts on the chip.
    pub fn spi_transaction(
        &mut self,
        i: usize,
        operations: &mut [Operation<'_, u8>],
        cost_ns: u64,
    ) -> Result<(), crate::pins::SpiError> {
        let Some(radio) = self.radios.get_mut(i) else {
            return Err(crate::pins::SpiError);
        };
        let bus = &mut radio.spi;
        bus.stats.transactions += 1;
        bus.stats.busy_ns += cost_ns;
        let fail = if bus.fail_next > 0 {
            bus.fail_next -= 1;
            true
        } else {
            // Draw only when errors are on: runs without them keep their random sequence.
            bus.error_rate > 0.0 && self.rng.chance(bus.error_rate)
        };
        if fail {
            if let Some(r) = self.radios.get_mut(i) {
                r.spi.stats.failed += 1;
            }
            return Err(crate::pins::SpiError);
        }
        self.spi(i, operations);
        Ok(())
    }

    /// One SPI transaction on radio `i` (instantaneous except for `DelayNs` operations).
    pub fn spi(&mut self, i: usize, operations: &mut [Operation<'_, u8>]) {
        self.process_due();
        let mut session = Session::default();
        for operation in operations.iter_mut() {
            match operation {
                Operation::Read(buffer) => {
                    for byte in buffer.iter_mut() {
                        *byte = self.spi_byte(i, &mut session, 0x00);
                    }
                }
                Operation::Write(bytes) => {
                    for &byte in bytes.iter() {
                        self.spi_byte(i, &mut session, byte);
                    }
                }
                Operation::Transfer(read, write) => {
                    for k in 0..read.len().max(write.len()) {
                        let mosi = write.get(k).copied().unwrap_or(0x00);
                        let miso = self.spi_byte(i, &mut session, mosi);
                        if let Some(slot) = read.get_mut(k) {
                            *slot = miso;
                        }
                    }
                }
                Operation::TransferInPlace(buffer) => {
                    for byte in buffer.iter_mut() {
                        *byte = self.spi_byte(i, &mut session, *byte);
                    }
                }
                Operation::DelayNs(ns) => {
                    let until = self.now_ns().saturating_add(u64::from(*ns));
                    self.advance_to(until);
                }
            }
        }
        self.process_due();
        self.update_irq(i);
    }

    fn spi_byte(&mut self, i: usize, session: &mut Session, mosi: u8) -> u8 {
        let Some(address) = session.address else {
            session.address = Some(mosi & 0x7F);
            session.write = mosi & 0x80 != 0;
            return match self.radios.get(i).map(|r| r.chip.fault) {
                Some(Fault::Unplugged { miso }) => miso,
                _ => 0x00,
            };
        };
        // Bursts auto-increment the address, except on the FIFO register (datasheet §3.1).
        if address != 0x7F {
            session.address = Some((address + 1) & 0x7F);
        }
        let write = session.write;
        // The live RSSI needs the whole medium; only compute it when 0x26 is read.
        let live_rssi = if !write && address == 0x26 {
            self.live_rssi(i)
        } else {
            0
        };
        self.with_chip(i, |chip, now, ctx| {
            if write {
                chip.spi_write(address, mosi, now, ctx);
                0x00
            } else {
                chip.spi_read(address, live_rssi)
            }
        })
        .unwrap_or(0xFF)
    }
}
