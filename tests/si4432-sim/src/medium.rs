//! The public face of the RF medium: configuration, adding radios, moving them, injecting
//! interference and faults, and reading the trace.

use core::time::Duration;
use std::cell::RefCell;
use std::rc::Rc;

use crate::chip::{ChipState, Fault, Physical};
use crate::modem::{ModemSettings, airtime_ns, bits_on_air};
use crate::packet::PacketFormat;
use crate::pins::{SimDelay, SimIrq, SimSdn, SimSpi};
use crate::trace::{RadioId, TraceFrame};
use crate::world::SpiStats;
use crate::world::World;
use sim_exec::VirtualTime;

/// Medium-wide settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumConfig {
    /// Probability that a receiver misses a frame it could otherwise have received.
    /// Default 0.
    pub packet_loss: f64,
    /// Path-loss exponent: 2.0 is free space (default); 2.7–3.5 approximates ground clutter.
    pub path_loss_exponent: f64,
    /// Capture effect: a frame this many dB stronger than the one a receiver is tracking
    /// takes over if it arrives before that one's sync word. `None` (default): first wins.
    pub capture_threshold_db: Option<f64>,
}

impl Default for MediumConfig {
    fn default() -> Self {
        Self {
            packet_loss: 0.0,
            path_loss_exponent: 2.0,
            capture_threshold_db: None,
        }
    }
}

/// Where a radio is and what its hardware is like.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadioConfig {
    /// Position in metres (x, y, z).
    pub position_m: [f64; 3],
    /// Antenna gain in dBi, applied on TX and RX. Default 0.
    pub antenna_gain_dbi: f64,
    /// Crystal error in ppm: the radiated carrier is scaled by (1 + ppm·10⁻⁶). Default 0.
    pub crystal_error_ppm: f64,
    /// Die temperature the ADC reports, in °C. Default 25.
    pub temperature_c: f64,
    /// Supply voltage the battery monitor reports (0x1B), in V. Default 3.3.
    pub supply_v: f64,
    /// SPI clock of the MCU's bus to this chip, Hz: every transaction takes
    /// bytes × 8 / clock plus [`RadioConfig::spi_overhead_ns`] of virtual time. Default
    /// [`SPI_CLOCK_F405_HZ`]; 0 makes transactions instantaneous (and drops the overhead).
    pub spi_clock_hz: u32,
    /// Fixed cost of one SPI transaction (nSEL, DMA set-up, the task's wake-up), ns.
    /// Default [`SPI_OVERHEAD_NS`].
    pub spi_overhead_ns: u64,
    /// Time from an nIRQ falling edge to the task waiting for it running (EXTI/GPIOTE
    /// interrupt, executor wake-up), ns. A wait that starts with the line already low
    /// returns at once, as embassy's `wait_for_low` does. Default [`IRQ_LATENCY_NS`].
    pub irq_latency_ns: u64,
}

/// The flight board's RFM22B bus: SPI3 at APB1 42 MHz ÷ 8 (`hardware/brushedsparky/README.md`,
/// flight-fw board.rs).
pub const SPI_CLOCK_F405_HZ: u32 = 5_250_000;
/// The module's RFM22B bus: nRF52840 SPIM at 8 MHz (`hardware/taulink-module/README.md`, module-fw
/// board.rs).
pub const SPI_CLOCK_NRF52840_HZ: u32 = 8_000_000;
/// Default per-transaction SPI overhead: nSEL set-up/hold, DMA start and the async
/// driver's completion wake-up, a few µs on a Cortex-M4 at 168 MHz or an nRF52840.
pub const SPI_OVERHEAD_NS: u64 = 3_000;
/// Default nIRQ latency: interrupt entry, the executor waking and polling the task.
pub const IRQ_LATENCY_NS: u64 = 5_000;

impl Default for RadioConfig {
    fn default() -> Self {
        Self {
            position_m: [0.0; 3],
            antenna_gain_dbi: 0.0,
            crystal_error_ppm: 0.0,
            temperature_c: 25.0,
            supply_v: 3.3,
            spi_clock_hz: SPI_CLOCK_F405_HZ,
            spi_overhead_ns: SPI_OVERHEAD_NS,
            irq_latency_ns: IRQ_LATENCY_NS,
        }
    }
}

impl RadioConfig {
    /// A radio at `position_m` with default hardware.
    pub fn at(position_m: [f64; 3]) -> Self {
        Self {
            position_m,
            ..Self::default()
        }
    }

    /// The same radio on an ideal bus: SPI transactions and nIRQ wake-ups take no time
    /// (tests of the chip's own timing to the nanosecond).
    pub fn with_instant_bus(self) -> Self {
        Self {
            spi_clock_hz: 0,
            spi_overhead_ns: 0,
            irq_latency_ns: 0,
            ..self
        }
    }

    pub(crate) fn physical(&self) -> Physical {
        Physical {
            crystal_error_ppm: self.crystal_error_ppm,
            temperature_c: self.temperature_c,
            supply_v: self.supply_v,
        }
    }
}

/// A burst of foreign energy on some channel (another system, a jammer, a motor).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interference {
    /// Start of the burst.
    pub start: Duration,
    /// End of the burst (exclusive).
    pub end: Duration,
    /// Centre frequency, in Hz.
    pub center_hz: f64,
    /// Occupied bandwidth, in Hz.
    pub bandwidth_hz: f64,
    /// Power at every receiver, in dBm.
    pub power_dbm: f64,
}

/// Handle to the RF medium of one simulation (cheap to clone).
#[derive(Clone)]
pub struct Medium {
    pub(crate) world: Rc<RefCell<World>>,
}

/// Everything a driver needs for one chip: the embedded-hal endpoints plus a test handle.
#[derive(Debug)]
pub struct RadioHandle {
    /// This radio's id in the medium.
    pub id: RadioId,
    /// SPI bus to the chip (blocking and async `SpiDevice`).
    pub spi: SimSpi,
    /// The nIRQ line (`InputPin` and async `Wait`).
    pub nirq: SimIrq,
    /// The SDN pin (`OutputPin`).
    pub sdn: SimSdn,
    /// Virtual-time delay (blocking and async `DelayNs`).
    pub delay: SimDelay,
    /// Inspection and fault injection.
    pub chip: ChipHandle,
}

impl Medium {
    /// Add a radio; returns its embedded-hal endpoints. The chip starts powered and READY with
    /// `ipor`/`ichiprdy` pending, as a module looks after the MCU has booted.
    pub fn add_radio(&self, config: RadioConfig) -> RadioHandle {
        let index = self.world.borrow_mut().add_radio(config);
        let world = &self.world;
        RadioHandle {
            id: RadioId(index),
            spi: SimSpi::new(world.clone(), index),
            nirq: SimIrq::new(world.clone(), index),
            sdn: SimSdn::new(world.clone(), index),
            delay: SimDelay::new(world.clone()),
            chip: ChipHandle {
                world: world.clone(),
                index,
            },
        }
    }

    /// Move a radio.
    pub fn set_position(&self, radio: RadioId, position_m: [f64; 3]) {
        if let Some(r) = self.world.borrow_mut().radios.get_mut(radio.0) {
            r.config.position_m = position_m;
        }
    }

    /// Extra loss between two radios (both directions), e.g. an obstacle or an attenuator.
    pub fn set_attenuation(&self, a: RadioId, b: RadioId, loss_db: f64) {
        self.world
            .borrow_mut()
            .attenuation_db
            .insert((a.0.min(b.0), a.0.max(b.0)), loss_db);
    }

    /// Change the random packet loss probability.
    pub fn set_packet_loss(&self, probability: f64) {
        self.world.borrow_mut().air.config.packet_loss = probability;
    }

    /// Replace the whole medium configuration.
    pub fn set_config(&self, config: MediumConfig) {
        self.world.borrow_mut().air.config = config;
    }

    /// Put a packet on air for `to` from an ideal transmitter that is not a radio (the
    /// lora-rs `inject_rx` pattern): formatted with `to`'s own registers (carrier, bit rate,
    /// preamble, sync, its check header, length, CRC, whitening), arriving at `power_dbm` at
    /// every radio, starting now. `to` must be in RX to hear it. Returns the trace id; the
    /// trace names the sender `RadioId::INJECTED`.
    pub fn inject_packet(&self, to: RadioId, payload: &[u8], power_dbm: f64) -> Option<u64> {
        self.world.borrow_mut().inject(to.0, payload, power_dbm)
    }

    /// Add an interference burst.
    pub fn add_interference(&self, burst: Interference) {
        self.world.borrow_mut().air.bursts.push(burst);
    }

    /// Power radio `to` receives from radio `from` on `carrier_hz` at `tx_power_dbm`, in dBm.
    pub fn received_power_dbm(
        &self,
        from: RadioId,
        to: RadioId,
        carrier_hz: f64,
        tx_power_dbm: f64,
    ) -> f64 {
        self.world
            .borrow()
            .link_power_dbm(from.0, to.0, carrier_hz, tx_power_dbm)
    }

    /// A copy of the trace.
    pub fn trace(&self) -> Vec<TraceFrame> {
        self.world.borrow().air.trace.clone()
    }

    /// Number of frames in the trace.
    pub fn trace_len(&self) -> usize {
        self.world.borrow().air.trace.len()
    }

    /// Look at the trace without copying it.
    pub fn with_trace<R>(&self, f: impl FnOnce(&[TraceFrame]) -> R) -> R {
        f(&self.world.borrow().air.trace)
    }

    /// Forget the trace so far (long runs).
    pub fn clear_trace(&self) {
        self.world.borrow_mut().air.clear_trace();
    }

    /// Current virtual time.
    pub fn now(&self) -> Duration {
        Duration::from_nanos(self.world.borrow().now_ns())
    }

    /// The virtual time the chips and tasks share (for a board's [`crate::SimClock`]).
    pub fn time(&self) -> VirtualTime {
        self.world.borrow().time.clone()
    }

    /// The earliest instant a chip changes on its own (a byte on air, a PLL settling), ns;
    /// `None` when every chip is idle. For a co-simulation that steps the medium itself.
    pub fn next_event_ns(&self) -> Option<u64> {
        self.world.borrow().next_chip_event_ns()
    }

    /// Moves the whole medium to `t_ns` (every chip event up to it, in time order; no task
    /// runs): what a co-simulation that is not an async task calls between its steps.
    /// Earlier instants are ignored (time only moves forward).
    pub fn advance_to_ns(&self, t_ns: u64) {
        let mut world = self.world.borrow_mut();
        if t_ns > world.now_ns() {
            world.advance_to(t_ns);
        }
    }
}

/// Test-side access to one chip: look at it and break it.
#[derive(Clone)]
pub struct ChipHandle {
    world: Rc<RefCell<World>>,
    index: usize,
}

impl ChipHandle {
    fn with<R>(&self, f: impl FnOnce(&mut World) -> R) -> R {
        f(&mut self.world.borrow_mut())
    }

    /// Register value without SPI side effects (status registers are the latched bits).
    pub fn peek(&self, address: u8) -> u8 {
        self.with(|w| {
            w.radios.get(self.index).map_or(0, |r| match address {
                0x03 => r.chip.status1,
                0x04 => r.chip.status2,
                _ => r.chip.reg(address),
            })
        })
    }

    /// Overwrite a register behind the driver's back (register corruption, e.g. a glitch).
    pub fn poke(&self, address: u8, value: u8) {
        self.with(|w| {
            if let Some(r) = w.radios.get_mut(self.index) {
                r.chip.set_reg(address, value);
            }
            w.update_irq(self.index);
        });
    }

    /// Inject or clear a hardware fault.
    pub fn set_fault(&self, fault: Fault) {
        self.with(|w| {
            if let Some(r) = w.radios.get_mut(self.index) {
                r.chip.fault = fault;
            }
            w.update_irq(self.index);
        });
    }

    /// The next `count` SPI transactions to this chip fail: they take their time, reach
    /// nothing and return [`SpiError`](crate::SpiError) (a glitch on the bus, a DMA error).
    pub fn fail_spi_transactions(&self, count: u32) {
        self.with(|w| {
            if let Some(r) = w.radios.get_mut(self.index) {
                r.spi.fail_next = count;
            }
        });
    }

    /// Every SPI transaction to this chip fails with probability `p` (from the simulation's
    /// seed, so runs repeat); 0 turns it off.
    pub fn set_spi_error_rate(&self, p: f64) {
        self.with(|w| {
            if let Some(r) = w.radios.get_mut(self.index) {
                r.spi.error_rate = p;
            }
        });
    }

    /// SPI statistics of this chip so far.
    pub fn spi_stats(&self) -> SpiStats {
        self.with(|w| {
            w.radios
                .get(self.index)
                .map_or(SpiStats::default(), |r| r.spi.stats)
        })
    }

    /// A power-on reset right now (brown-out): registers lost, `ipor` after the POR time.
    pub fn power_on_reset(&self) {
        self.with(|w| {
            w.with_chip(self.index, |chip, now, ctx| chip.power_on_reset(now, ctx));
            w.update_irq(self.index);
        });
    }

    /// Operating state.
    pub fn state(&self) -> ChipState {
        self.with(|w| {
            w.radios
                .get(self.index)
                .map_or(ChipState::Shutdown, |r| r.chip.state())
        })
    }

    /// nIRQ level (true = low = interrupt pending).
    pub fn nirq_is_low(&self) -> bool {
        self.with(|w| w.radios.get(self.index).is_some_and(|r| r.chip.nirq_low()))
    }

    /// Bytes waiting in the TX FIFO.
    pub fn tx_fifo_len(&self) -> usize {
        self.with(|w| w.radios.get(self.index).map_or(0, |r| r.chip.tx_fifo.len()))
    }

    /// Bytes waiting in the RX FIFO.
    pub fn rx_fifo_len(&self) -> usize {
        self.with(|w| w.radios.get(self.index).map_or(0, |r| r.chip.rx_fifo.len()))
    }

    /// The modem settings the registers describe right now.
    pub fn modem(&self) -> Option<ModemSettings> {
        self.with(|w| {
            w.radios
                .get(self.index)
                .map(|r| ModemSettings::from_registers(&r.chip.regs))
        })
    }

    /// Airtime of a `payload_len`-byte packet with the current registers: preamble, sync,
    /// header, length byte, payload and CRC as configured, at the TX bit rate (Manchester
    /// doubles it). Add `PLL_SETTLE_NS` (or more from STANDBY) for txon → `ipksent`.
    pub fn airtime(&self, payload_len: usize) -> Duration {
        self.with(|w| {
            w.radios.get(self.index).map_or(Duration::ZERO, |r| {
                let modem = ModemSettings::from_registers(&r.chip.regs);
                let format = PacketFormat::from_registers(&r.chip.regs);
                let bits = bits_on_air(
                    u32::from(format.preamble_nibbles) * 4,
                    format.bytes_after_preamble(payload_len),
                    modem.manchester,
                );
                Duration::from_nanos(airtime_ns(bits, modem.tx_bit_rate_bps))
            })
        })
    }

    /// nSEL falls: an SPI transaction clocked byte by byte starts ([`ChipHandle::clock_byte`];
    /// a board whose MCU's SPI controller shifts single bytes, rather than an embedded-hal
    /// transaction). An injected bus error decides here whether it reaches the chip.
    pub fn select(&self) {
        self.with(|w| w.select(self.index));
    }

    /// One byte clocked while selected: MOSI in, what the chip drives on MISO out; `None`
    /// when nothing drives MISO (not selected, so SDO is tri-stated, or the transaction was
    /// failed by an injected bus error). The first byte is the address (bit 7 = write),
    /// the next ones data, bursts auto-incrementing except at 0x7F, exactly as
    /// [`crate::SimSpi`]'s transactions; each byte acts on the chip when it is clocked.
    pub fn clock_byte(&self, mosi: u8) -> Option<u8> {
        self.with(|w| w.clock_byte(self.index, mosi))
    }

    /// nSEL rises: the transaction ends.
    pub fn deselect(&self) {
        self.with(|w| w.deselect(self.index));
    }

    /// From now on every change of nIRQ is kept with its time for
    /// [`ChipHandle::take_nirq_edges`] (a board feeding the line into an MCU model).
    pub fn record_nirq_edges(&self) {
        self.with(|w| {
            if let Some(r) = w.radios.get_mut(self.index) {
                r.irq.edges.get_or_insert_with(Vec::new);
            }
        });
    }

    /// The changes of nIRQ since the last call, in time order: (time ns, low). Empty unless
    /// [`ChipHandle::record_nirq_edges`] was called.
    pub fn take_nirq_edges(&self) -> Vec<(u64, bool)> {
        self.with(|w| {
            w.radios
                .get_mut(self.index)
                .and_then(|r| r.irq.edges.as_mut())
                .map(std::mem::take)
                .unwrap_or_default()
        })
    }

    /// Number of falling edges nIRQ has made so far.
    pub fn nirq_falling_edges(&self) -> u64 {
        self.with(|w| w.radios.get(self.index).map_or(0, |r| r.irq.falling_edges))
    }
}

impl core::fmt::Debug for Medium {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let world = self.world.borrow();
        f.debug_struct("Medium")
            .field("now_ns", &world.now_ns())
            .field("radios", &world.radios.len())
            .field("frames", &world.air.trace.len())
            .finish()
    }
}

impl core::fmt::Debug for ChipHandle {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ChipHandle")
            .field("radio", &self.index)
            .finish()
    }
}
