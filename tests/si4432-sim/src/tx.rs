//! The transmit half of the packet handler: builds the frame and streams the TX FIFO.
//!
//! At TX start the frame length is fixed (0x3E), so the airtime is known. Sync, header and
//! length go on air at once; each payload byte leaves the FIFO when its first bit is due, so
//! a driver that refills at "almost empty" keeps up and one that does not causes an
//! underflow (FIFO error interrupt; the missing bytes go out as 0x00 and the CRC catches
//! them). After the last bit: `ipksent`, txon clears and the chip returns to READY/TUNE
//! (datasheet §6.2, 0x07 txon description).

use crate::air::{BitClock, Transmission};
use crate::chip::{
    Activity, Chip, Ctx, EZMAC_CRCERROR, EZMAC_PKSENT, EZMAC_PKVALID, STATUS_FFUNFL,
};
use crate::modem::{DataSource, ModemSettings, Modulation};
use crate::packet::{Crc16, PacketFormat, Pn9};
use crate::registers::{addr, irq1, mode1};

#[derive(Debug)]
pub(crate) struct TxState {
    pub id: u64,
    clock: BitClock,
    /// Payload bytes to send from the FIFO.
    payload_len: usize,
    /// Payload bytes already taken from the FIFO.
    fetched: usize,
    /// Stream index of payload byte 0.
    payload_offset: usize,
    /// Last bit on air; `None` for a carrier that stays on.
    end_ns: Option<u64>,
    crc: Option<Crc16>,
    pn9: Option<Pn9>,
    /// The FIFO ran dry during this frame.
    underflowed: bool,
}

impl TxState {
    pub fn next_event_ns(&self) -> Option<u64> {
        let end = self.end_ns?;
        if self.fetched < self.payload_len {
            Some(
                self.clock
                    .byte_start_ns(self.payload_offset + self.fetched)
                    .min(end),
            )
        } else {
            Some(end)
        }
    }

    /// Put one byte on air: CRC over the plain byte (if covered), then whitening.
    fn emit(&mut self, id: u64, byte: u8, crc_covers: bool, ctx: &mut Ctx<'_>) {
        if crc_covers && let Some(crc) = self.crc.as_mut() {
            crc.update(byte);
        }
        let on_air = self.pn9.as_mut().map_or(byte, |pn9| byte ^ pn9.next_byte());
        ctx.air.append(id, byte, on_air);
    }

    fn emit_crc(&mut self, id: u64, ctx: &mut Ctx<'_>) {
        if let Some(crc) = self.crc {
            // Model choice: bytes that never came out of the FIFO are not what the CRC engine
            // saw, so an underflowed frame always fails the receiver's CRC check.
            let value = if self.underflowed {
                !crc.value()
            } else {
                crc.value()
            };
            let [hi, lo] = value.to_be_bytes();
            self.emit(id, hi, false, ctx);
            self.emit(id, lo, false, ctx);
        }
    }
}

impl Chip {
    /// The carrier as radiated: the register value scaled by this crystal's error.
    pub(crate) fn radiated_carrier_hz(&self, modem: &ModemSettings) -> f64 {
        modem.carrier_hz * (1.0 + self.physical.crystal_error_ppm * 1e-6)
    }

    /// PLL settled with txon: put the frame on air.
    pub(crate) fn begin_tx(&mut self, now_ns: u64, ctx: &mut Ctx<'_>) -> Option<u64> {
        let modem = ModemSettings::from_registers(&self.regs);
        let format = PacketFormat::from_registers(&self.regs);
        self.ezmac_latched &= !(EZMAC_PKSENT | EZMAC_PKVALID | EZMAC_CRCERROR);
        let decodable =
            modem.data_source == DataSource::Fifo && modem.modulation != Modulation::Unmodulated;
        let chips_per_bit = if modem.manchester { 2.0 } else { 1.0 };
        let clock = BitClock {
            start_ns: now_ns,
            preamble_bits: u32::from(format.preamble_nibbles) * 4,
            ns_per_bit: chips_per_bit * 1e9 / modem.tx_bit_rate_bps.max(1.0),
        };
        let payload_len = usize::from(format.packet_length);
        let (stream_len, end_ns) = if decodable {
            let len = format.bytes_after_preamble(payload_len);
            (len, Some(clock.byte_start_ns(len)))
        } else {
            (0, None)
        };
        let transmission = Transmission {
            id: 0,
            radio: self.me,
            clock,
            end_ns: end_ns.unwrap_or(u64::MAX),
            carrier_hz: self.radiated_carrier_hz(&modem),
            modem,
            sync: format.sync.clone(),
            stream: Vec::with_capacity(stream_len),
            stream_len,
            decodable,
            rx_power_dbm: Vec::new(),
        };
        let id = ctx.air.start(
            transmission,
            Vec::with_capacity(stream_len),
            ctx.radio_count,
        );
        let mut state = TxState {
            id,
            clock,
            payload_len: if decodable { payload_len } else { 0 },
            fetched: 0,
            payload_offset: 0,
            end_ns,
            crc: format.crc.filter(|_| format.handler_tx).map(Crc16::new),
            pn9: modem.whitening.then(Pn9::default),
            underflowed: false,
        };
        if decodable {
            for &b in &format.sync {
                ctx.air.append(id, b, b);
            }
            let mut prefix = format.sync.len();
            if format.handler_tx {
                let covered = !format.crc_data_only;
                for &b in format.tx_header_bytes() {
                    state.emit(id, b, covered, ctx);
                    prefix += 1;
                }
                if !format.fixed_length {
                    state.emit(id, format.packet_length, covered, ctx);
                    prefix += 1;
                }
            }
            state.payload_offset = prefix;
            if payload_len == 0 {
                state.emit_crc(id, ctx);
            }
        }
        self.activity = Activity::Tx(state);
        Some(id)
    }

    /// A payload byte is due, or the frame has ended.
    pub(crate) fn tx_step(&mut self, now_ns: u64, ctx: &mut Ctx<'_>) {
        let Activity::Tx(state) = &mut self.activity else {
            return;
        };
        let id = state.id;
        let fetch_due = state.fetched < state.payload_len
            && state
                .clock
                .byte_start_ns(state.payload_offset + state.fetched)
                <= now_ns;
        if fetch_due {
            let threshold = self
                .regs
                .get(usize::from(addr::TX_FIFO_CONTROL_2))
                .copied()
                .unwrap_or(0)
                & 0x3F;
            let (byte, events) = self.tx_fifo.pop(threshold);
            if events.error {
                self.status1 |= irq1::FIFO_ERROR;
                self.device_flags |= STATUS_FFUNFL;
                state.underflowed = true;
                ctx.air.mark_damaged(id);
            }
            if events.almost_empty {
                self.status1 |= irq1::TX_FIFO_ALMOST_EMPTY;
            }
            state.emit(id, byte.unwrap_or(0), true, ctx);
            state.fetched += 1;
            if state.fetched == state.payload_len {
                state.emit_crc(id, ctx);
            }
            return;
        }
        if state.end_ns.is_some_and(|end| end <= now_ns) {
            self.status1 |= irq1::PACKET_SENT;
            self.ezmac_latched |= EZMAC_PKSENT;
            let mode = self.reg(addr::OPERATING_MODE_1) & !mode1::TXON;
            self.set_reg(addr::OPERATING_MODE_1, mode);
            self.activity = Activity::Idle;
            ctx.air.prune(now_ns);
        }
    }
}
