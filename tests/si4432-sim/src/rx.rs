//! The receive half: preamble detection, sync search, header check, length, payload into the
//! RX FIFO, CRC, and the interrupts each step raises (datasheet §6.2, Figure 32).
//!
//! A receiver locks onto the first frame it can demodulate (modem match, above sensitivity,
//! preamble still long enough to detect, not randomly lost). Each byte is then delivered
//! when its last bit arrives, with bit errors drawn from the signal-to-noise-plus-
//! interference ratio at that moment, so collisions and interference bursts corrupt exactly
//! the bytes they overlap.

use crate::air::{Air, BitClock};
use crate::chip::{Activity, Chip, Ctx, EZMAC_CRCERROR, EZMAC_PKVALID, STATUS_HEADERR};
use crate::modem::ModemSettings;
use crate::packet::{Crc16, PacketFormat, Pn9};
use crate::propagation::{bit_error_rate, dbm_to_mw, mw_to_dbm, noise_floor_dbm, rssi_register};
use crate::registers::{addr, irq1, irq2, mode1};
use crate::trace::Outcome;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Stage {
    PreambleValid,
    SyncDetect,
    GiveUp(Outcome),
    Header,
    Length,
    Payload,
    Crc,
    Raw,
    /// Payload complete and no CRC to check.
    Done,
}

#[derive(Debug)]
pub(crate) struct Lock {
    pub(crate) tx_id: u64,
    pub(crate) clock: BitClock,
    pub(crate) tx_stream_len: usize,
    pub(crate) tx_carrier_hz: f64,
    pub(crate) signal_dbm: f64,
    pub(crate) stage: Stage,
    pub(crate) next_ns: u64,
    pub(crate) format: PacketFormat,
    pub(crate) modem: ModemSettings,
    pub(crate) carrier_hz: f64,
    /// Next stream index to receive.
    pub(crate) index: usize,
    pub(crate) pn9: Option<Pn9>,
    pub(crate) crc: Option<Crc16>,
    pub(crate) header: Vec<u8>,
    pub(crate) length: usize,
    pub(crate) payload_received: usize,
    pub(crate) crc_received: Vec<u8>,
    pub(crate) bit_errors: u32,
    /// Receiver noise power (mW) and the bit error rate without interference.
    pub(crate) noise_mw: f64,
    pub(crate) clean_ber: f64,
}

#[derive(Debug)]
pub(crate) struct RxState {
    pub listening_since_ns: u64,
    pub(crate) lock: Option<Box<Lock>>,
}

impl RxState {
    pub fn next_event_ns(&self) -> Option<u64> {
        self.lock.as_ref().map(|lock| lock.next_ns)
    }

    /// True once a sync word has been detected (EzMAC pkrx).
    pub fn receiving(&self) -> bool {
        self.lock.as_ref().is_some_and(|l| {
            !matches!(
                l.stage,
                Stage::PreambleValid | Stage::SyncDetect | Stage::GiveUp(_)
            )
        })
    }

    /// Leaving RX mid-frame.
    pub fn abort(self, me: usize, ctx: &mut Ctx<'_>) {
        if let Some(lock) = self.lock {
            ctx.air.record(lock.tx_id, me, Outcome::Aborted);
        }
    }
}

/// How a lock ended.
enum Finish {
    Valid,
    CrcError,
    Quiet(Outcome),
}

impl Chip {
    /// The RSSI register as the medium makes it now: noise + every frame and burst in the
    /// IF bandwidth (raw = 2·(dBm + 122) + rssi_off steps).
    pub(crate) fn live_rssi(&self, air: &Air, now_ns: u64) -> u8 {
        let modem = ModemSettings::from_registers(&self.regs);
        let carrier_hz = self.radiated_carrier_hz(&modem);
        let in_band_mw = dbm_to_mw(noise_floor_dbm(modem.rx_bit_rate_bps))
            + air.interference_mw(self.me, now_ns, carrier_hz, modem.if_bandwidth_hz, None);
        rssi_register(
            mw_to_dbm(in_band_mw),
            self.reg(addr::PREAMBLE_DETECTION) & 0x07,
        )
    }

    /// `irssi`: in RX, the in-band power reached the 0x27 threshold. Evaluated when RX
    /// starts and whenever a frame starts (not for interference bursts).
    pub(crate) fn check_rssi_threshold(&mut self, now_ns: u64, ctx: &Ctx<'_>) {
        if matches!(self.activity, Activity::Rx(_))
            && self.live_rssi(ctx.air, now_ns) >= self.reg(addr::RSSI_THRESHOLD)
        {
            self.status2 |= irq2::RSSI;
        }
    }

    /// Something is due for the frame this receiver is locked to.
    pub(crate) fn rx_step(&mut self, now_ns: u64, ctx: &mut Ctx<'_>) {
        let me = self.me;
        let Activity::Rx(rx) = &mut self.activity else {
            return;
        };
        let Some(lock) = rx.lock.as_mut() else {
            return;
        };
        if lock.next_ns > now_ns {
            return;
        }
        let mut finish = None;
        match lock.stage {
            Stage::PreambleValid => {
                self.status2 |= irq2::VALID_PREAMBLE;
                let tx_sync = ctx
                    .air
                    .get(lock.tx_id)
                    .map(|tx| tx.sync.clone())
                    .unwrap_or_default();
                let found = tx_sync
                    .windows(lock.format.sync.len())
                    .position(|w| w == lock.format.sync.as_slice())
                    .map(|p| p + lock.format.sync.len());
                let sync_end_ns = lock.clock.byte_end_ns(tx_sync.len().saturating_sub(1));
                match found {
                    None => {
                        lock.stage = Stage::GiveUp(Outcome::SyncMismatch);
                        lock.next_ns = sync_end_ns;
                    }
                    Some(end) => {
                        let ber = ber_now(lock, me, now_ns, ctx);
                        let sync_bits = 8 * lock.format.sync.len() as i32;
                        if ctx.rng.chance(1.0 - (1.0 - ber).powi(sync_bits)) {
                            lock.stage = Stage::GiveUp(Outcome::SyncCorrupted);
                            lock.next_ns = sync_end_ns;
                        } else {
                            lock.stage = Stage::SyncDetect;
                            lock.index = end;
                            lock.next_ns = lock.clock.byte_end_ns(end.saturating_sub(1));
                        }
                    }
                }
            }
            Stage::SyncDetect => {
                self.status2 |= irq2::SYNC_WORD;
                let interference_mw = ctx.air.interference_mw(
                    me,
                    now_ns,
                    lock.carrier_hz,
                    lock.modem.if_bandwidth_hz,
                    None,
                );
                let in_band =
                    interference_mw + dbm_to_mw(noise_floor_dbm(lock.modem.rx_bit_rate_bps));
                // The locked frame itself is part of `interference_mw` here (exclude = None).
                self.rssi_latch = Some(rssi_register(mw_to_dbm(in_band), lock.format.rssi_offset));
                self.afc_raw = if lock.modem.afc_pull_in_hz > 0.0 {
                    let steps = ((lock.tx_carrier_hz - lock.carrier_hz) / lock.modem.step_hz)
                        .round()
                        .clamp(-512.0, 511.0);
                    (steps as i16 as u16) & 0x3FF
                } else {
                    0
                };
                lock.pn9 = lock.modem.whitening.then(Pn9::default);
                lock.crc = lock.format.crc.map(Crc16::new);
                lock.stage = if !lock.format.handler_rx {
                    Stage::Raw
                } else if lock.format.header_len > 0 {
                    Stage::Header
                } else {
                    after_header(lock)
                };
                if lock.stage == Stage::Done {
                    finish = Some(Finish::Valid);
                } else {
                    lock.next_ns = lock.clock.byte_end_ns(lock.index);
                }
            }
            Stage::GiveUp(outcome) => finish = Some(Finish::Quiet(outcome)),
            Stage::Done => finish = Some(Finish::Valid),
            Stage::Header | Stage::Length | Stage::Payload | Stage::Crc | Stage::Raw => {
                let byte = receive_byte(lock, me, now_ns, ctx);
                let covered = !lock.format.crc_data_only;
                match lock.stage {
                    Stage::Header => {
                        if covered {
                            update_crc(lock, byte);
                        }
                        let slot = addr::RECEIVED_HEADER_3 + lock.header.len() as u8;
                        if let Some(reg) = self.regs.get_mut(usize::from(slot)) {
                            *reg = byte;
                        }
                        lock.header.push(byte);
                        if lock.header.len() == lock.format.header_len {
                            if lock.format.header_accepted(&lock.header) {
                                lock.stage = after_header(lock);
                            } else {
                                self.device_flags |= STATUS_HEADERR;
                                finish = Some(Finish::Quiet(Outcome::HeaderMismatch));
                            }
                        }
                    }
                    Stage::Length => {
                        if covered {
                            update_crc(lock, byte);
                        }
                        if let Some(reg) =
                            self.regs.get_mut(usize::from(addr::RECEIVED_PACKET_LENGTH))
                        {
                            *reg = byte;
                        }
                        lock.length = usize::from(byte);
                        lock.stage = after_length(lock);
                    }
                    Stage::Payload | Stage::Raw => {
                        update_crc(lock, byte);
                        let threshold = self
                            .regs
                            .get(usize::from(addr::RX_FIFO_CONTROL))
                            .copied()
                            .unwrap_or(0)
                            & 0x3F;
                        let events = self.rx_fifo.push(byte, threshold);
                        if events.error {
                            self.status1 |= irq1::FIFO_ERROR;
                            self.device_flags |= crate::chip::STATUS_FFOVFL;
                        }
                        if events.almost_full {
                            self.status1 |= irq1::RX_FIFO_ALMOST_FULL;
                        }
                        lock.payload_received += 1;
                        if lock.stage == Stage::Raw {
                            if lock.index >= lock.tx_stream_len {
                                finish = Some(Finish::Quiet(Outcome::Delivered {
                                    bit_errors: lock.bit_errors,
                                }));
                            }
                        } else if lock.payload_received >= lock.length {
                            lock.stage = if lock.crc.is_some() {
                                Stage::Crc
                            } else {
                                Stage::Done
                            };
                        }
                    }
                    _ => {
                        lock.crc_received.push(byte);
                        if lock.crc_received.len() == 2 {
                            let expected = lock
                                .crc
                                .map(|c| c.value().to_be_bytes().to_vec())
                                .unwrap_or_default();
                            finish = Some(if expected == lock.crc_received {
                                Finish::Valid
                            } else {
                                Finish::CrcError
                            });
                        }
                    }
                }
                if finish.is_none() && lock.stage == Stage::Done {
                    finish = Some(Finish::Valid);
                }
                lock.next_ns = lock.clock.byte_end_ns(lock.index);
            }
        }
        if let Some(finish) = finish {
            self.finish_rx(finish, now_ns, ctx);
        }
    }

    fn finish_rx(&mut self, finish: Finish, now_ns: u64, ctx: &mut Ctx<'_>) {
        let Activity::Rx(rx) = &mut self.activity else {
            return;
        };
        let Some(lock) = rx.lock.take() else {
            return;
        };
        let me = self.me;
        match finish {
            Finish::Valid => {
                if lock.format.fixed_length {
                    self.set_reg(addr::RECEIVED_PACKET_LENGTH, lock.format.packet_length);
                }
                self.status1 |= irq1::VALID_PACKET;
                self.ezmac_latched |= EZMAC_PKVALID;
                ctx.air.record(
                    lock.tx_id,
                    me,
                    Outcome::Delivered {
                        bit_errors: lock.bit_errors,
                    },
                );
                // rxon clears after a valid packet unless multi-packet RX (0x08 rxmpk) is set.
                if self.reg(addr::OPERATING_MODE_2) & 0x10 == 0 {
                    let mode = self.reg(addr::OPERATING_MODE_1) & !mode1::RXON;
                    self.set_reg(addr::OPERATING_MODE_1, mode);
                    self.activity = Activity::Idle;
                    return;
                }
            }
            Finish::CrcError => {
                self.status1 |= irq1::CRC_ERROR;
                self.ezmac_latched |= EZMAC_CRCERROR;
                ctx.air.record(
                    lock.tx_id,
                    me,
                    Outcome::CrcError {
                        bit_errors: lock.bit_errors,
                    },
                );
            }
            Finish::Quiet(outcome) => ctx.air.record(lock.tx_id, me, outcome),
        }
        // Still in RX: search again (RSSI live again until the next sync).
        self.rssi_latch = None;
        self.scan_air(now_ns, ctx, Some(lock.tx_id));
    }
}

fn update_crc(lock: &mut Lock, byte: u8) {
    if let Some(crc) = lock.crc.as_mut() {
        crc.update(byte);
    }
}

fn after_header(lock: &mut Lock) -> Stage {
    if lock.format.fixed_length {
        lock.length = usize::from(lock.format.packet_length);
        after_length(lock)
    } else {
        Stage::Length
    }
}

fn after_length(lock: &Lock) -> Stage {
    match (lock.length, lock.crc.is_some()) {
        (0, true) => Stage::Crc,
        (0, false) => Stage::Done,
        _ => Stage::Payload,
    }
}

/// Bit error rate for the locked frame at `now_ns` (signal against noise + interference).
fn ber_now(lock: &Lock, me: usize, now_ns: u64, ctx: &Ctx<'_>) -> f64 {
    let interference = ctx.air.interference_mw(
        me,
        now_ns,
        lock.carrier_hz,
        lock.modem.if_bandwidth_hz,
        Some(lock.tx_id),
    );
    if interference == 0.0 {
        return lock.clean_ber;
    }
    bit_error_rate(lock.signal_dbm, mw_to_dbm(lock.noise_mw + interference))
}

/// The next stream byte as this receiver demodulates it: the transmitted byte with bit
/// errors, or noise once the transmitter has stopped; then de-whitened.
fn receive_byte(lock: &mut Lock, me: usize, now_ns: u64, ctx: &mut Ctx<'_>) -> u8 {
    let k = lock.index;
    lock.index += 1;
    let sent = ctx.air.get(lock.tx_id).and_then(|tx| {
        if lock.clock.byte_end_ns(k) <= tx.end_ns {
            tx.stream.get(k).copied()
        } else {
            None
        }
    });
    let mut byte = match sent {
        Some(byte) => {
            let ber = ber_now(lock, me, now_ns, ctx);
            let mut byte = byte;
            if ctx.rng.chance(1.0 - (1.0 - ber).powi(8)) {
                byte ^= 1 << ctx.rng.below(8);
                lock.bit_errors += 1;
            }
            byte
        }
        None => ctx.rng.byte(),
    };
    if let Some(pn9) = lock.pn9.as_mut() {
        byte ^= pn9.next_byte();
    }
    byte
}
