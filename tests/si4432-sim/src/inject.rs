//! Frames from an ideal transmitter that is not a radio: the lora-rs `inject_rx` pattern
//! (lora-rs), for receiver tests that do not want to drive a second chip.
//!
//! The frame is built from the *receiver's* own registers — carrier, clock-recovery bit
//! rate, preamble, sync word, its check header (so the header passes), length byte, CRC and
//! whitening — so it matches by construction, and starts on air at once with a chosen power.

use crate::air::{BitClock, Transmission};
use crate::modem::{DataSource, ModemSettings, Modulation};
use crate::packet::{Crc16, PacketFormat, Pn9};
use crate::trace::RadioId;
use crate::world::World;

impl RadioId {
    /// The sender recorded in the trace for injected frames.
    pub const INJECTED: RadioId = RadioId(usize::MAX);
}

impl World {
    /// Put a frame carrying `payload` on air for radio `target`, arriving at `power_dbm`
    /// at every radio. Returns the frame id.
    pub fn inject(&mut self, target: usize, payload: &[u8], power_dbm: f64) -> Option<u64> {
        let radio = self.radios.get(target)?;
        let regs = &radio.chip.regs;
        let format = PacketFormat::from_registers(regs);
        let mut modem = ModemSettings::from_registers(regs);
        modem.tx_bit_rate_bps = modem.rx_bit_rate_bps;
        modem.data_source = DataSource::Fifo;
        if modem.modulation == Modulation::Unmodulated {
            modem.modulation = Modulation::Gfsk;
        }
        let carrier_hz = radio.chip.radiated_carrier_hz(&modem);

        let mut logical = format.sync.clone();
        let mut covered = Vec::new();
        if format.handler_rx {
            covered.extend(format.check_header.iter().take(format.header_len));
            if !format.fixed_length {
                covered.push(payload.len().min(255) as u8);
            }
        }
        let mut crc = format.crc.filter(|_| format.handler_rx).map(Crc16::new);
        for &b in covered.iter().filter(|_| !format.crc_data_only) {
            crc.iter_mut().for_each(|c| c.update(b));
        }
        for &b in payload {
            crc.iter_mut().for_each(|c| c.update(b));
        }
        logical.extend(&covered);
        logical.extend(payload);
        if let Some(crc) = crc {
            logical.extend(crc.value().to_be_bytes());
        }
        let mut pn9 = modem.whitening.then(Pn9::default);
        let on_air: Vec<u8> = logical
            .iter()
            .enumerate()
            .map(|(k, &b)| match pn9.as_mut() {
                Some(pn9) if k >= format.sync.len() => b ^ pn9.next_byte(),
                _ => b,
            })
            .collect();

        let chips_per_bit = if modem.manchester { 2.0 } else { 1.0 };
        let clock = BitClock {
            start_ns: self.now_ns(),
            preamble_bits: u32::from(format.preamble_nibbles) * 4,
            ns_per_bit: chips_per_bit * 1e9 / modem.tx_bit_rate_bps.max(1.0),
        };
        let stream_len = on_air.len();
        let transmission = Transmission {
            id: 0,
            radio: RadioId::INJECTED.0,
            clock,
            end_ns: clock.byte_start_ns(stream_len),
            carrier_hz,
            modem,
            sync: format.sync.clone(),
            stream: on_air,
            stream_len,
            decodable: true,
            rx_power_dbm: Vec::new(),
        };
        self.air.prune(self.now_ns());
        let count = self.radios.len();
        let id = self.air.start(transmission, logical, count);
        self.air.set_powers(id, vec![power_dbm; count]);
        for to in 0..count {
            self.with_chip(to, |chip, now, ctx| chip.consider(id, now, ctx));
            self.update_irq(to);
        }
        Some(id)
    }
}
