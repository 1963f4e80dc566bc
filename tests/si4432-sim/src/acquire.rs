//! Whether a receiver hears a frame at all: RX state, modem match, link budget, preamble
//! still detectable, capture, random loss. The winner becomes the receiver's `Lock`; every
//! loser gets its reason in the trace.

use crate::chip::{Activity, Chip, Ctx, EZMAC_CRCERROR, EZMAC_PKVALID};
use crate::modem::ModemSettings;
use crate::packet::PacketFormat;
use crate::propagation::{bit_error_rate, dbm_to_mw, noise_floor_dbm, sensitivity_dbm};
use crate::rx::{Lock, RxState, Stage};
use crate::trace::Outcome;

impl Chip {
    /// PLL settled with rxon: start searching, and look at frames already on air.
    pub(crate) fn begin_rx(&mut self, now_ns: u64, ctx: &mut Ctx<'_>) {
        self.activity = Activity::Rx(RxState {
            listening_since_ns: now_ns,
            lock: None,
        });
        self.rssi_latch = None;
        self.ezmac_latched &= !(EZMAC_PKVALID | EZMAC_CRCERROR);
        self.scan_air(now_ns, ctx, None);
        self.check_rssi_threshold(now_ns, ctx);
    }

    /// Look at frames already on air. After a frame ends (`finished`), the search only
    /// locks; it does not overwrite outcomes already recorded for the other frames.
    pub(crate) fn scan_air(&mut self, now_ns: u64, ctx: &mut Ctx<'_>, finished: Option<u64>) {
        let ids: Vec<u64> = ctx
            .air
            .transmissions()
            .filter(|tx| tx.active_at(now_ns) && Some(tx.id) != finished)
            .map(|tx| tx.id)
            .collect();
        for id in ids {
            self.consider_into(id, now_ns, ctx, finished.is_none());
        }
    }

    /// A frame `id` is on air: lock onto it if this receiver can, and record why not otherwise.
    pub(crate) fn consider(&mut self, id: u64, now_ns: u64, ctx: &mut Ctx<'_>) {
        self.consider_into(id, now_ns, ctx, true);
    }

    /// `consider`; failures go to the trace only if `record_failure`.
    fn consider_into(&mut self, id: u64, now_ns: u64, ctx: &mut Ctx<'_>, record_failure: bool) {
        if let Err(outcome) = self.try_lock(id, now_ns, ctx)
            && record_failure
        {
            ctx.air.record(id, self.me, outcome);
        }
    }

    /// Lock onto frame `id`, or say why not.
    fn try_lock(&mut self, id: u64, now_ns: u64, ctx: &mut Ctx<'_>) -> Result<(), Outcome> {
        let me = self.me;
        let Some((clock, tx_stream_len, tx_carrier_hz, tx_modem, signal_dbm, decodable, from)) =
            ctx.air.get(id).map(|tx| {
                (
                    tx.clock,
                    tx.stream_len,
                    tx.carrier_hz,
                    tx.modem,
                    tx.power_at(me),
                    tx.decodable,
                    tx.radio,
                )
            })
        else {
            return Ok(());
        };
        if from == me {
            return Ok(());
        }
        let Activity::Rx(rx) = &self.activity else {
            return Err(Outcome::NotListening);
        };
        if !decodable {
            return Err(Outcome::NoData);
        }
        let modem = ModemSettings::from_registers(&self.regs);
        let carrier_hz = self.radiated_carrier_hz(&modem);
        if let Err(mismatch) = modem.can_receive(&tx_modem, tx_carrier_hz, carrier_hz) {
            return Err(Outcome::Mismatch(mismatch));
        }
        if signal_dbm < sensitivity_dbm(modem.rx_bit_rate_bps) - 6.0 {
            return Err(Outcome::TooWeak);
        }
        let format = PacketFormat::from_registers(&self.regs);
        let detect_from = clock.start_ns.max(rx.listening_since_ns).max(now_ns);
        let preamble_valid_ns = clock.after_bits_ns(
            detect_from,
            u32::from(format.preamble_threshold_nibbles.max(1)) * 4,
        );
        if preamble_valid_ns > clock.byte_start_ns(0) {
            return Err(Outcome::MissedPreamble);
        }
        let loss = ctx.air.config.packet_loss;
        if ctx.rng.chance(loss) {
            return Err(Outcome::RandomLoss);
        }
        if let Some(current) = &rx.lock {
            let capture = ctx
                .air
                .config
                .capture_threshold_db
                .is_some_and(|threshold_db| {
                    matches!(current.stage, Stage::PreambleValid | Stage::SyncDetect)
                        && signal_dbm >= current.signal_dbm + threshold_db
                });
            if !capture {
                return Err(Outcome::Busy);
            }
            ctx.air.record(current.tx_id, me, Outcome::Captured);
        }
        let lock = Lock {
            tx_id: id,
            clock,
            tx_stream_len,
            tx_carrier_hz,
            signal_dbm,
            stage: Stage::PreambleValid,
            next_ns: preamble_valid_ns,
            pn9: None,
            crc: None,
            header: Vec::with_capacity(4),
            length: 0,
            payload_received: 0,
            crc_received: Vec::with_capacity(2),
            bit_errors: 0,
            noise_mw: dbm_to_mw(noise_floor_dbm(modem.rx_bit_rate_bps)),
            clean_ber: bit_error_rate(signal_dbm, noise_floor_dbm(modem.rx_bit_rate_bps)),
            index: 0,
            carrier_hz,
            modem,
            format,
        };
        if let Activity::Rx(rx) = &mut self.activity {
            rx.lock = Some(Box::new(lock));
        }
        Ok(())
    }
}
