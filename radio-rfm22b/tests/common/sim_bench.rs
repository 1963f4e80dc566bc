//! The real driver on virtual Si4432s (`si4432-sim`): a bench of radio nodes in one RF medium,
//! run in virtual time, and the exchanges the `against_sim*` tests are built from.
//!
//! Each node owns an `Rfm22b` on a chip's SPI, nIRQ, SDN and delay. Tests run driver calls
//! as tasks of the deterministic executor; `Bench::run` gives up after `RUN_LIMIT` of virtual
//! time, so a driver that hangs fails the test instead of stalling it.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code

use core::cell::RefCell;
use core::future::Future;
use core::time::Duration;
use std::rc::Rc;

use radio_rfm22b::{
    Carrier, Config, Error, ModemConfig, PacketConfig, Rfm22b, RxOutcome, RxPacket,
};
use si4432_sim::{
    ChipHandle, Medium, Outcome, RadioConfig, RadioId, SimDelay, SimIrq, SimSdn, SimSpi,
    Simulation, TraceFrame,
};

/// The driver on a virtual chip.
pub type SimRfm = Rfm22b<SimSpi, SimIrq, SimSdn, SimDelay>;
/// The driver's error on the virtual bus (which cannot fail).
pub type SimError = Error<si4432_sim::SpiError>;

/// Hop channel 0 of every test link: 433.000 MHz.
pub const CARRIER_HZ: u32 = 433_000_000;
/// Distance between the two ends of the standard link, in metres.
pub const DISTANCE_M: f64 = 1_000.0;
/// The driver's default output power (`Config::new`: `TxPower::MAX`), in dBm.
pub const TX_POWER_DBM: f64 = 20.0;
/// Time the receiver gets to arm RX before the transmitter starts: more than the chip's
/// 200 µs PLL settle (datasheet Table 11), so the preamble is never missed.
pub const RX_LEAD_US: u64 = 1_000;
/// Generous TX timeout: a 255-byte packet at 9.6 kbit/s is on air for ~221 ms.
pub const TX_TIMEOUT_US: u32 = 400_000;
/// The driver polls chip-ready every 1 ms after a software reset; the virtual crystal is
/// ready after 600 µs, so the first poll sees it.
pub const CHIP_READY_POLL: Duration = Duration::from_millis(1);
/// Virtual time after which `Bench::run` declares the driver hung.
pub const RUN_LIMIT: Duration = Duration::from_secs(10);

/// The Tau Labs (bit rate, deviation) pairs the tests exercise, slowest to fastest.
pub const RATES: [(u32, u32); 4] = [
    (9_600, 30_000),
    (57_600, 45_000),
    (128_000, 90_000),
    (256_000, 150_000),
];

/// A configuration at `bit_rate_bps` / `deviation_hz` with the default packet handler
/// (sync 2D D4, no header, CRC-CCITT, variable length) on 433 MHz.
pub fn config(bit_rate_bps: u32, deviation_hz: u32) -> Config {
    config_with(bit_rate_bps, deviation_hz, PacketConfig::new())
}

/// As [`config`] with a chosen packet handler.
pub fn config_with(bit_rate_bps: u32, deviation_hz: u32, packet: PacketConfig) -> Config {
    let modem = ModemConfig::try_new(bit_rate_bps, deviation_hz).unwrap();
    Config::new(modem, packet, Carrier::new(CARRIER_HZ))
}

/// How long the driver's `init` takes on a healthy chip with SDN wired (SDN pulse, then one
/// chip-ready poll), measured once on a scratch simulation. The driver's SDN timings are
/// private; `init_resets_through_sdn_…` checks this figure against the datasheet.
pub fn reset_time() -> Duration {
    let bench = Bench::new(0);
    let node = bench.node_at([0.0; 3]);
    let config = config(57_600, 45_000);
    let (info, elapsed) = bench.op(&node, async move |r| r.init(config).await);
    info.unwrap();
    elapsed
}

/// The SDN pulse alone (high, then low until the chip's power-on reset is over): a reset
/// of an absent chip ends there, at the failed probe.
pub fn sdn_pulse() -> Duration {
    reset_time() - CHIP_READY_POLL
}

/// `len` bytes that differ from position to position and from `seed` to `seed`.
pub fn pattern(len: usize, seed: u8) -> Vec<u8> {
    (0..len)
        .map(|i| (i as u8).wrapping_mul(31).wrapping_add(seed) ^ 0x5A)
        .collect()
}

/// One radio end: the driver plus the chip's test handle.
#[derive(Clone)]
pub struct Node {
    radio: Rc<RefCell<Option<SimRfm>>>,
    /// The chip's id in the medium.
    pub id: RadioId,
    /// Inspection and fault injection.
    pub chip: ChipHandle,
}

impl Node {
    /// Runs `op` on the driver. The driver is moved out for the duration, so no `RefCell`
    /// borrow is held across an await; two tasks using one node at once is a test bug.
    pub async fn with<T>(&self, op: impl AsyncFnOnce(&mut SimRfm) -> T) -> T {
        let mut radio = self
            .radio
            .borrow_mut()
            .take()
            .expect("the driver is in use by another task");
        let out = op(&mut radio).await;
        *self.radio.borrow_mut() = Some(radio);
        out
    }
}

/// What one `transmit` / `receive` pair produced.
#[derive(Debug)]
pub struct Exchange {
    /// The transmitter's result.
    pub sent: Result<(), SimError>,
    /// The receiver's result.
    pub received: Result<RxOutcome, SimError>,
    /// The payload the receiver got (empty unless `RxOutcome::Packet`).
    pub payload: Vec<u8>,
    /// From `transmit` being called to it returning.
    pub tx_elapsed: Duration,
    /// From `receive` being called to it returning.
    pub rx_elapsed: Duration,
}

impl Exchange {
    /// The received packet; panics with the whole exchange otherwise.
    #[track_caller]
    pub fn packet(&self) -> RxPacket {
        match self.received {
            Ok(RxOutcome::Packet(p)) => p,
            _ => panic!("no packet: {self:?}"),
        }
    }
}

/// A simulation, its medium and helpers to run the driver in it.
pub struct Bench {
    /// The executor and virtual clock.
    pub sim: Simulation,
    /// The RF medium.
    pub medium: Medium,
}

impl Bench {
    /// An empty medium whose randomness is fixed by `seed`.
    pub fn new(seed: u64) -> Self {
        let sim = Simulation::new(seed);
        let medium = sim.medium();
        Self { sim, medium }
    }

    /// A node at `position_m` with ideal hardware on an ideal bus (SPI and nIRQ take no
    /// time, so tests can time the driver to the nanosecond), driver built with its SDN pin.
    pub fn node_at(&self, position_m: [f64; 3]) -> Node {
        self.node(RadioConfig::at(position_m).with_instant_bus())
    }

    /// A node with the given hardware (and its bus: SPI time and nIRQ latency as configured).
    pub fn node(&self, config: RadioConfig) -> Node {
        let handle = self.medium.add_radio(config);
        let radio = Rfm22b::new(handle.spi, handle.nirq, handle.sdn, handle.delay);
        Node {
            radio: Rc::new(RefCell::new(Some(radio))),
            id: handle.id,
            chip: handle.chip,
        }
    }

    /// Two nodes `DISTANCE_M` apart on the x axis, both initialised with `config`.
    pub fn link(&self, config: Config) -> (Node, Node) {
        let a = self.node_at([0.0, 0.0, 0.0]);
        let b = self.node_at([DISTANCE_M, 0.0, 0.0]);
        self.init(&a, config).unwrap();
        self.init(&b, config).unwrap();
        (a, b)
    }

    /// Current virtual time.
    pub fn now(&self) -> Duration {
        self.sim.now()
    }

    /// Runs `future` as a task until it finishes; panics if it takes longer than
    /// `RUN_LIMIT` of virtual time (a hang).
    pub fn run<T: 'static>(&self, future: impl Future<Output = T> + 'static) -> T {
        let task = self.sim.spawn(future);
        let start = self.now();
        assert!(
            self.sim.run_until_or(RUN_LIMIT, || task.is_finished()),
            "the driver did not return within {RUN_LIMIT:?} of virtual time (started at {start:?})"
        );
        task.take().unwrap()
    }

    /// Runs one driver operation on `node` and returns its result and how much virtual time
    /// it took.
    pub fn op<T: 'static>(
        &self,
        node: &Node,
        op: impl AsyncFnOnce(&mut SimRfm) -> T + 'static,
    ) -> (T, Duration) {
        let node = node.clone();
        let start = self.now();
        let out = self.run(async move { node.with(op).await });
        (out, self.now() - start)
    }

    /// `init(config)` on `node`.
    pub fn init(&self, node: &Node, config: Config) -> Result<radio_rfm22b::ChipInfo, SimError> {
        self.op(node, async move |r| r.init(config).await).0
    }

    /// A sleeping future of `us` microseconds of virtual time (for tasks).
    pub fn pause(&self, us: u64) -> si4432_sim::Sleep {
        self.sim.delay().sleep_ns(us * 1_000)
    }

    /// `to` listens for up to `rx_timeout_us` while `from` sends `payload` `RX_LEAD_US`
    /// after RX was armed, with `TX_TIMEOUT_US`. Runs until both calls return.
    pub fn exchange(&self, from: &Node, to: &Node, payload: &[u8], rx_timeout_us: u32) -> Exchange {
        self.exchange_with(from, to, payload, TX_TIMEOUT_US, rx_timeout_us)
    }

    /// As [`Bench::exchange`] with a chosen TX timeout.
    pub fn exchange_with(
        &self,
        from: &Node,
        to: &Node,
        payload: &[u8],
        tx_timeout_us: u32,
        rx_timeout_us: u32,
    ) -> Exchange {
        let (from, to) = (from.clone(), to.clone());
        let payload = payload.to_vec();
        let (rx_medium, tx_medium) = (self.medium.clone(), self.medium.clone());
        let receiver = self.sim.spawn(async move {
            let start = rx_medium.now();
            let mut buf = [0u8; 255];
            let received = to
                .with(async |r| r.receive(&mut buf, rx_timeout_us).await)
                .await;
            let len = match received {
                Ok(RxOutcome::Packet(p)) => p.len,
                _ => 0,
            };
            (received, buf[..len].to_vec(), rx_medium.now() - start)
        });
        let lead = self.pause(RX_LEAD_US);
        let transmitter = self.sim.spawn(async move {
            lead.await;
            let start = tx_medium.now();
            let sent = from
                .with(async |r| r.transmit(&payload, tx_timeout_us).await)
                .await;
            (sent, tx_medium.now() - start)
        });
        assert!(
            self.sim.run_until_or(RUN_LIMIT, || {
                receiver.is_finished() && transmitter.is_finished()
            }),
            "an exchange did not finish within {RUN_LIMIT:?}"
        );
        let (received, payload, rx_elapsed) = receiver.take().unwrap();
        let (sent, tx_elapsed) = transmitter.take().unwrap();
        Exchange {
            sent,
            received,
            payload,
            tx_elapsed,
            rx_elapsed,
        }
    }

    /// The outcome the medium recorded at `at` for the last frame in the trace.
    pub fn last_outcome_at(&self, at: &Node) -> Option<Outcome> {
        self.medium
            .with_trace(|t| t.last().and_then(|f| f.outcome_at(at.id)))
    }

    /// The last frame in the trace.
    pub fn last_frame(&self) -> Option<TraceFrame> {
        self.medium.with_trace(|t| t.last().cloned())
    }

    /// Received power from `from` at `to` on the link carrier at the driver's TX power, as
    /// the medium's path-loss model computes it, in dBm.
    pub fn link_power_dbm(&self, from: &Node, to: &Node) -> f64 {
        self.medium
            .received_power_dbm(from.id, to.id, f64::from(CARRIER_HZ), TX_POWER_DBM)
    }
}
