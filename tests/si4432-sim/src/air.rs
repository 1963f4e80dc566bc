//! The shared air: frames in flight, their bit timing, interference, and the trace.
//!
//! A `Transmission` is the bit stream one chip radiates. Its bytes after the preamble are
//! appended as the transmitter's packet handler produces them (payload bytes leave the TX
//! FIFO one byte-time before they are complete on air), and receivers read byte *k* when
//! its last bit has arrived, so a receiver never sees a byte the transmitter has not sent.

use core::time::Duration;
use std::collections::VecDeque;

use crate::medium::{Interference, MediumConfig};
use crate::modem::ModemSettings;
use crate::propagation::dbm_to_mw;
use crate::trace::{Outcome, RadioId, Reception, TraceFrame};

/// How long an ended transmission is kept after its last bit. Receivers read byte k exactly
/// when it ends, so nothing needs it later; a little slack keeps pruning order-independent.
const KEEP_AFTER_END_NS: u64 = 1_000_000;

/// One frame (or carrier) on air.
#[derive(Clone, Debug)]
pub(crate) struct Transmission {
    pub id: u64,
    pub radio: usize,
    pub clock: BitClock,
    /// End of the last bit; `u64::MAX` for a carrier that stays on until aborted.
    pub end_ns: u64,
    pub carrier_hz: f64,
    pub modem: ModemSettings,
    pub sync: Vec<u8>,
    /// Bytes after the preamble, as on air (whitened), appended as produced.
    pub stream: Vec<u8>,
    /// Number of stream bytes the frame will have.
    pub stream_len: usize,
    /// False for carriers without packet data.
    pub decodable: bool,
    /// Received power at each radio (index = radio), filled in by the world.
    pub rx_power_dbm: Vec<f64>,
}

/// Bit timing of one frame: when each byte after the preamble starts and ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BitClock {
    /// Start of the preamble.
    pub start_ns: u64,
    /// Preamble length in bits.
    pub preamble_bits: u32,
    /// Nanoseconds per data bit (Manchester included).
    pub ns_per_bit: f64,
}

impl BitClock {
    /// Time the first bit of stream byte `k` goes on air.
    pub fn byte_start_ns(&self, k: usize) -> u64 {
        let bits = f64::from(self.preamble_bits) + 8.0 * k as f64;
        self.start_ns
            .saturating_add((bits * self.ns_per_bit).round() as u64)
    }

    /// Time the last bit of stream byte `k` has arrived.
    pub fn byte_end_ns(&self, k: usize) -> u64 {
        self.byte_start_ns(k + 1)
    }

    /// Time `bits` bits after `from_ns`.
    pub fn after_bits_ns(&self, from_ns: u64, bits: u32) -> u64 {
        from_ns.saturating_add((f64::from(bits) * self.ns_per_bit).round() as u64)
    }
}

impl Transmission {
    /// Whether the frame is on air at `now_ns`.
    pub fn active_at(&self, now_ns: u64) -> bool {
        self.clock.start_ns <= now_ns && now_ns < self.end_ns
    }

    /// Power this frame puts into receiver `radio`, in dBm.
    pub fn power_at(&self, radio: usize) -> f64 {
        self.rx_power_dbm.get(radio).copied().unwrap_or(-200.0)
    }
}

/// Everything radiated, plus the medium's configuration and trace.
#[derive(Debug, Default)]
pub(crate) struct Air {
    pub config: MediumConfig,
    pub bursts: Vec<Interference>,
    transmissions: VecDeque<Transmission>,
    next_id: u64,
    pub trace: Vec<TraceFrame>,
    /// Id of `trace[0]` (the trace can be cleared).
    trace_base: u64,
}

impl Air {
    /// An empty air with `config`.
    pub fn new(config: MediumConfig) -> Self {
        Self {
            config,
            ..Self::default()
        }
    }

    /// Put a new transmission on air; returns its id.
    pub fn start(&mut self, mut tx: Transmission, trace_bytes: Vec<u8>, radio_count: usize) -> u64 {
        let id = self.next_id;
        self.next_id += 1;
        tx.id = id;
        tx.rx_power_dbm = vec![-200.0; radio_count];
        self.trace.push(TraceFrame {
            id,
            radio: RadioId(tx.radio),
            start: Duration::from_nanos(tx.clock.start_ns),
            end: if tx.end_ns == u64::MAX {
                Duration::MAX
            } else {
                Duration::from_nanos(tx.end_ns)
            },
            carrier_hz: tx.carrier_hz,
            bit_rate_bps: tx.modem.tx_bit_rate_bps,
            tx_power_dbm: tx.modem.tx_power_dbm,
            bytes: trace_bytes,
            damaged: false,
            power_dbm: Vec::new(),
            receptions: Vec::new(),
        });
        self.transmissions.push_back(tx);
        id
    }

    /// The transmission `id`, while it is kept.
    pub fn get(&self, id: u64) -> Option<&Transmission> {
        let first = self.transmissions.front()?.id;
        self.transmissions
            .get(usize::try_from(id.checked_sub(first)?).ok()?)
    }

    /// Mutable access to transmission `id`.
    pub fn get_mut(&mut self, id: u64) -> Option<&mut Transmission> {
        let first = self.transmissions.front()?.id;
        self.transmissions
            .get_mut(usize::try_from(id.checked_sub(first)?).ok()?)
    }

    /// All kept transmissions (active and recently ended).
    pub fn transmissions(&self) -> impl Iterator<Item = &Transmission> {
        self.transmissions.iter()
    }

    /// The trace entry of frame `id`, if not cleared.
    pub fn trace_mut(&mut self, id: u64) -> Option<&mut TraceFrame> {
        let index = usize::try_from(id.checked_sub(self.trace_base)?).ok()?;
        self.trace.get_mut(index)
    }

    /// Forget the trace so far.
    pub fn clear_trace(&mut self) {
        self.trace_base = self.next_id;
        self.trace.clear();
    }

    /// Append one produced byte: `logical` to the trace, `on_air` to the stream.
    pub fn append(&mut self, id: u64, logical: u8, on_air: u8) {
        if let Some(tx) = self.get_mut(id) {
            tx.stream.push(on_air);
        }
        if let Some(frame) = self.trace_mut(id) {
            frame.bytes.push(logical);
        }
    }

    /// Set the per-radio received powers of frame `id`.
    pub fn set_powers(&mut self, id: u64, powers_dbm: Vec<f64>) {
        if let Some(frame) = self.trace_mut(id) {
            frame.power_dbm.clone_from(&powers_dbm);
        }
        if let Some(tx) = self.get_mut(id) {
            tx.rx_power_dbm = powers_dbm;
        }
    }

    /// Mark frame `id` damaged (aborted, or the TX FIFO ran dry).
    pub fn mark_damaged(&mut self, id: u64) {
        if let Some(frame) = self.trace_mut(id) {
            frame.damaged = true;
        }
    }

    /// Cut transmission `id` off at `now_ns` (TX turned off mid-frame).
    pub fn abort(&mut self, id: u64, now_ns: u64) {
        if let Some(tx) = self.get_mut(id) {
            tx.end_ns = tx.end_ns.min(now_ns);
        }
        if let Some(frame) = self.trace_mut(id) {
            frame.end = Duration::from_nanos(now_ns);
            frame.damaged = true;
        }
    }

    /// Record (or replace) what `radio` made of frame `id`.
    pub fn record(&mut self, id: u64, radio: usize, outcome: Outcome) {
        if let Some(frame) = self.trace_mut(id) {
            let power_dbm = frame.power_dbm.get(radio).copied().unwrap_or(-200.0);
            let reception = Reception {
                radio: RadioId(radio),
                power_dbm,
                outcome,
            };
            match frame.receptions.iter_mut().find(|r| r.radio.0 == radio) {
                Some(existing) => *existing = reception,
                None => frame.receptions.push(reception),
            }
        }
    }

    /// Drop transmissions that ended long enough ago that no receiver can still need them.
    pub fn prune(&mut self, now_ns: u64) {
        while self
            .transmissions
            .front()
            .is_some_and(|tx| tx.end_ns.saturating_add(KEEP_AFTER_END_NS) < now_ns)
        {
            self.transmissions.pop_front();
        }
    }

    /// Interference power at receiver `radio` tuned to `carrier_hz` with `bandwidth_hz` at
    /// `now_ns`, from every other frame and burst that overlaps its channel, in mW.
    pub fn interference_mw(
        &self,
        radio: usize,
        now_ns: u64,
        carrier_hz: f64,
        bandwidth_hz: f64,
        exclude: Option<u64>,
    ) -> f64 {
        let frames: f64 = self
            .transmissions
            .iter()
            .filter(|tx| Some(tx.id) != exclude && tx.radio != radio && tx.active_at(now_ns))
            .filter(|tx| {
                let occupied = tx.modem.tx_bit_rate_bps + 2.0 * tx.modem.deviation_hz;
                (tx.carrier_hz - carrier_hz).abs() < (occupied + bandwidth_hz) / 2.0
            })
            .map(|tx| dbm_to_mw(tx.power_at(radio)))
            .sum();
        let bursts: f64 = self
            .bursts
            .iter()
            .filter(|b| {
                b.start.as_nanos() <= u128::from(now_ns) && u128::from(now_ns) < b.end.as_nanos()
            })
            .filter(|b| (b.center_hz - carrier_hz).abs() < (b.bandwidth_hz + bandwidth_hz) / 2.0)
            .map(|b| dbm_to_mw(b.power_dbm))
            .sum();
        frames + bursts
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bit_clock_places_bytes_after_the_preamble() {
        // 10 kbit/s → 100 µs per bit; 32 preamble bits.
        let clock = BitClock {
            start_ns: 1_000,
            preamble_bits: 32,
            ns_per_bit: 100_000.0,
        };
        assert_eq!(clock.byte_start_ns(0), 1_000 + 3_200_000);
        assert_eq!(clock.byte_end_ns(0), 1_000 + 4_000_000);
        assert_eq!(clock.byte_end_ns(9), 1_000 + 3_200_000 + 8_000_000);
        assert_eq!(clock.after_bits_ns(500, 3), 300_500);
    }
}
