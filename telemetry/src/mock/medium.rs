//! The simulated RF medium: every transmission is kept with its time, frequency, header and
//! bytes; a listening radio receives a packet when it was listening (PLL settled) before the
//! preamble started, on the same frequency and rate, and the packet survives path loss,
//! collisions, injected loss and bit errors, and the chip's header and CRC checks.

use std::cell::RefCell;
use std::collections::{HashSet, VecDeque};
use std::rc::Rc;

use crate::checksum::crc16;
use crate::link::RateMode;
use crate::link::rate::{PREAMBLE_BYTES, SYNC_BYTES};
use sim_exec::VirtualTime;
use sim_rng::SplitMix64;

/// Propagation and impairment settings (shared by all nodes).
#[derive(Clone, Copy, Debug)]
pub struct ChannelModel {
    /// Extra random loss probability per reception (independent of signal level).
    pub loss: f64,
    /// Probability of each on-air bit flipping (header, length, payload, chip CRC).
    pub bit_error_rate: f64,
    /// Standard deviation of the RSSI wobble (fading), dB.
    pub fading_sigma_db: f64,
    /// Path-loss exponent (2 = free space).
    pub path_loss_exponent: f64,
    /// A packet survives an overlapping one on its frequency only if it is this much stronger.
    pub capture_db: f64,
}

impl Default for ChannelModel {
    fn default() -> Self {
        Self {
            loss: 0.0,
            bit_error_rate: 0.0,
            fading_sigma_db: 2.0,
            path_loss_exponent: 2.0,
            capture_db: 6.0,
        }
    }
}

/// One radio's placement and chip settings.
#[derive(Clone, Copy, Debug)]
pub struct Node {
    /// Position on a line, metres.
    pub position_m: f64,
    /// Transmit power, dBm (+20 = RFM22B maximum).
    pub tx_power_dbm: f64,
    /// Hardware header check on (the protocol's setting); off exposes foreign packets to the
    /// link CRC.
    pub check_header: bool,
    /// Chip CRC check on (the protocol's setting); off passes corrupted packets to the link
    /// CRC.
    pub chip_crc: bool,
}

impl Default for Node {
    fn default() -> Self {
        Self {
            position_m: 0.0,
            tx_power_dbm: 20.0,
            check_header: true,
            chip_crc: true,
        }
    }
}

/// Counters of what happened on the air.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MediumStats {
    /// Packets transmitted.
    pub transmitted: u64,
    /// Receptions delivered to a radio's FIFO.
    pub delivered: u64,
    /// Lost below sensitivity.
    pub lost_weak: u64,
    /// Lost to a collision.
    pub lost_collision: u64,
    /// Lost to injected random loss.
    pub lost_random: u64,
    /// Lost because the path was cut.
    pub lost_cut: u64,
    /// Dropped by the receiver's hardware header check.
    pub header_rejected: u64,
    /// Dropped by the receiver's chip CRC.
    pub chip_crc_rejected: u64,
    /// Delivered with at least one flipped bit (only possible with the chip CRC off, or by
    /// a CRC collision).
    pub corrupted_delivered: u64,
}

#[derive(Clone, Debug)]
struct Transmission {
    seq: u64,
    node: usize,
    start_us: u64,
    end_us: u64,
    frequency_hz: u32,
    rate: RateMode,
    header: [u8; 4],
    bytes: Vec<u8>,
}

#[derive(Clone, Debug)]
struct NodeState {
    node: Node,
    rate: RateMode,
    header: [u8; 4],
    /// Transmissions this node already evaluated in its current listen (several
    /// transmitters: the order they end in is not the order they started in).
    seen: HashSet<u64>,
}

struct State {
    time: VirtualTime,
    model: ChannelModel,
    rng: SplitMix64,
    nodes: Vec<NodeState>,
    air: VecDeque<Transmission>,
    next_seq: u64,
    cut: HashSet<(usize, usize)>,
    stats: MediumStats,
}

/// A delivered packet.
#[derive(Clone, Debug, PartialEq)]
pub struct Delivery {
    /// FIFO bytes.
    pub bytes: Vec<u8>,
    /// RSSI, dBm.
    pub rssi_dbm: i16,
    /// Sending node.
    pub from: usize,
}

/// The shared medium (cheap to clone).
#[derive(Clone)]
pub struct Medium {
    state: Rc<RefCell<State>>,
}

/// Approximate Si4432 sensitivity: −121 dBm at 2.4 kbps (datasheet, GFSK), worsening with
/// 10·log10 of the bit rate (noise bandwidth grows with it).
pub fn sensitivity_dbm(rate: RateMode) -> f64 {
    -121.0 + 10.0 * (f64::from(rate.bit_rate_bps()) / 2400.0).log10()
}

impl Medium {
    /// An empty medium on `time`.
    pub fn new(time: VirtualTime, model: ChannelModel, seed: u64) -> Self {
        Self {
            state: Rc::new(RefCell::new(State {
                time,
                model,
                rng: SplitMix64::new(seed),
                nodes: Vec::new(),
                air: VecDeque::new(),
                next_seq: 1,
                cut: HashSet::new(),
                stats: MediumStats::default(),
            })),
        }
    }

    /// Virtual time of the medium.
    pub fn time(&self) -> VirtualTime {
        self.state.borrow().time.clone()
    }

    /// Registers a radio; returns its node index.
    pub fn add_node(&self, node: Node) -> usize {
        let mut s = self.state.borrow_mut();
        s.nodes.push(NodeState {
            node,
            rate: RateMode::L50,
            header: [0; 4],
            seen: HashSet::new(),
        });
        s.nodes.len() - 1
    }

    /// Changes the impairments (e.g. mid-run).
    pub fn set_model(&self, model: ChannelModel) {
        self.state.borrow_mut().model = model;
    }

    /// Moves a node.
    pub fn set_position(&self, node: usize, position_m: f64) {
        if let Some(n) = self.state.borrow_mut().nodes.get_mut(node) {
            n.node.position_m = position_m;
        }
    }

    /// Cuts (or restores) the path between two nodes, both directions.
    pub fn set_cut(&self, a: usize, b: usize, cut: bool) {
        let key = (a.min(b), a.max(b));
        let mut s = self.state.borrow_mut();
        if cut {
            s.cut.insert(key);
        } else {
            s.cut.remove(&key);
        }
    }

    /// Air counters so far.
    pub fn stats(&self) -> MediumStats {
        self.state.borrow().stats
    }

    pub(crate) fn configure(&self, node: usize, rate: RateMode, header: [u8; 4]) {
        if let Some(n) = self.state.borrow_mut().nodes.get_mut(node) {
            n.rate = rate;
            n.header = header;
        }
    }

    pub(crate) fn transmit(
        &self,
        node: usize,
        start_us: u64,
        end_us: u64,
        frequency_hz: u32,
        bytes: &[u8],
    ) {
        let mut s = self.state.borrow_mut();
        let Some(n) = s.nodes.get(node) else {
            return;
        };
        let (rate, header) = (n.rate, n.header);
        let seq = s.next_seq;
        s.next_seq += 1;
        s.stats.transmitted += 1;
        s.air.push_back(Transmission {
            seq,
            node,
            start_us,
            end_us,
            frequency_hz,
            rate,
            header,
            bytes: bytes.to_vec(),
        });
        // Keep 200 ms of history: longer than any packet, so overlap checks stay complete.
        let horizon = start_us.saturating_sub(200_000);
        while s.air.front().is_some_and(|t| t.end_us < horizon) {
            s.air.pop_front();
        }
        s.time.wake_all_at(end_us);
    }

    /// `node` starts a new listen: nothing is evaluated yet (packets that started before
    /// it was ready are excluded by time in [`Medium::poll_reception`]).
    pub(crate) fn start_listening(&self, node: usize) {
        if let Some(n) = self.state.borrow_mut().nodes.get_mut(node) {
            n.seen.clear();
        }
    }

    /// When the packet `node` is in the middle of receiving ends: one on `frequency_hz`,
    /// at its rate, over an uncut path, that started after `ready_us` and whose sync word
    /// has arrived by now. The Si4432 driver completes such a packet past its receive
    /// timeout (radio-rfm22b `receive`); the mock radio does the same.
    pub(crate) fn arriving_end_us(
        &self,
        node: usize,
        frequency_hz: u32,
        ready_us: u64,
    ) -> Option<u64> {
        let s = self.state.borrow();
        let now = s.time.now_us();
        let me = s.nodes.get(node)?;
        s.air
            .iter()
            .filter(|t| {
                let sync_bits = ((PREAMBLE_BYTES + SYNC_BYTES) * 8) as u64;
                let sync_us = (sync_bits * 1_000_000).div_ceil(u64::from(t.rate.bit_rate_bps()));
                t.node != node
                    && t.frequency_hz == frequency_hz
                    && t.rate == me.rate
                    && t.start_us >= ready_us
                    && t.start_us + sync_us <= now
                    && t.end_us > now
                    && !s.cut.contains(&(node.min(t.node), node.max(t.node)))
            })
            .map(|t| t.end_us)
            .max()
    }

    /// The first packet for `node`, listening on `frequency_hz` since `ready_us`, that has
    /// fully arrived by now and survives; evaluates (and forgets) the ones that do not.
    pub(crate) fn poll_reception(
        &self,
        node: usize,
        frequency_hz: u32,
        ready_us: u64,
    ) -> Option<Delivery> {
        let mut guard = self.state.borrow_mut();
        let s = &mut *guard;
        let now = s.time.now_us();
        let me = s.nodes.get(node)?.clone();
        let mut candidates: Vec<Transmission> = s
            .air
            .iter()
            .filter(|t| {
                t.end_us <= now
                    && t.start_us >= ready_us
                    && t.node != node
                    && t.frequency_hz == frequency_hz
                    && !me.seen.contains(&t.seq)
            })
            .cloned()
            .collect();
        candidates.sort_by_key(|t| t.end_us);
        for t in candidates {
            if let Some(n) = s.nodes.get_mut(node) {
                n.seen.insert(t.seq);
            }
            if t.rate != me.rate {
                continue;
            }
            if let Some(d) = evaluate(s, &me, node, &t) {
                return Some(d);
            }
        }
        None
    }
}

fn distance_m(a: &Node, b: &Node) -> f64 {
    (a.position_m - b.position_m).abs().max(1.0)
}

fn received_power_dbm(model: &ChannelModel, from: &Node, to: &Node, frequency_hz: u32) -> f64 {
    // Free-space loss at 1 m, 20·log10(4π/λ), then the chosen exponent beyond it.
    let fspl_1m = 20.0 * f64::from(frequency_hz).log10() - 147.55;
    from.tx_power_dbm - fspl_1m - 10.0 * model.path_loss_exponent * distance_m(from, to).log10()
}

fn evaluate(s: &mut State, me: &NodeState, node: usize, t: &Transmission) -> Option<Delivery> {
    let from = s.nodes.get(t.node)?.node;
    if s.cut.contains(&(node.min(t.node), node.max(t.node))) {
        s.stats.lost_cut += 1;
        return None;
    }
    let model = s.model;
    let power = received_power_dbm(&model, &from, &me.node, t.frequency_hz)
        + s.rng.normal(model.fading_sigma_db);
    // Demodulation fails smoothly around sensitivity (about 1 dB per e-fold).
    let p_fail = 1.0 / (1.0 + ((power - sensitivity_dbm(me.rate)) / 1.0).exp());
    if s.rng.chance(p_fail) {
        s.stats.lost_weak += 1;
        return None;
    }
    let collided = s.air.iter().any(|q| {
        q.seq != t.seq
            && q.node != node
            && q.frequency_hz == t.frequency_hz
            && q.start_us < t.end_us
            && t.start_us < q.end_us
            && s.nodes.get(q.node).is_some_and(|qn| {
                received_power_dbm(&model, &qn.node, &me.node, q.frequency_hz)
                    > power - model.capture_db
            })
    });
    if collided {
        s.stats.lost_collision += 1;
        return None;
    }
    if s.rng.chance(model.loss) {
        s.stats.lost_random += 1;
        return None;
    }
    // The bits on air after sync: header, length, payload, chip CRC over those.
    let mut air = Vec::with_capacity(t.bytes.len() + 7);
    air.extend_from_slice(&t.header);
    air.push(t.bytes.len() as u8);
    air.extend_from_slice(&t.bytes);
    air.extend_from_slice(&crc16(&air).to_be_bytes());
    if model.bit_error_rate > 0.0 {
        for byte in air.iter_mut() {
            for bit in 0..8 {
                if s.rng.chance(model.bit_error_rate) {
                    *byte ^= 1 << bit;
                }
            }
        }
    }
    let (header, rest) = air.split_at_checked(4)?;
    if me.node.check_header && header != me.header {
        s.stats.header_rejected += 1;
        return None;
    }
    let (body, crc) = rest.split_at_checked(rest.len().checked_sub(2)?)?;
    let [len, payload @ ..] = body else {
        return None;
    };
    let [c0, c1] = crc else {
        return None;
    };
    let covered = air.get(..air.len() - 2)?;
    let chip_ok = crc16(covered) == u16::from_be_bytes([*c0, *c1]);
    if me.node.chip_crc && !chip_ok {
        s.stats.chip_crc_rejected += 1;
        return None;
    }
    // A flipped length byte: the chip reads that many bytes (bounded by what arrived).
    let delivered = payload.get(..usize::from(*len).min(payload.len()))?;
    if delivered != t.bytes.as_slice() {
        s.stats.corrupted_delivered += 1;
    }
    s.stats.delivered += 1;
    Some(Delivery {
        bytes: delivered.to_vec(),
        rssi_dbm: power.round() as i16,
        from: t.node,
    })
}
