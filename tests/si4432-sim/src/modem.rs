//! The modem as the registers describe it: carrier, bit rates, deviation, IF bandwidth, and
//! whether a transmitter's signal can be demodulated by a receiver.
//!
//! Formulas are the datasheet's (Si4432 rev B1,
//! "Carrier frequency" and the data-rate registers). The IF filter bandwidth (0x1C) is an approximation: exact at the codes the
//! Tau Labs / OpenLRSng tables use, interpolated elsewhere.

/// Modulation type (0x71 modtyp\[1:0\]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Modulation {
    /// 00: unmodulated carrier (carries no data).
    Unmodulated,
    /// 01: on-off keying.
    Ook,
    /// 10: frequency-shift keying.
    Fsk,
    /// 11: Gaussian FSK.
    Gfsk,
}

/// TX data source (0x71 dtmod\[1:0\]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataSource {
    /// 00: direct mode through a GPIO (not modelled: no decodable data on air).
    DirectGpio,
    /// 01: direct mode through SDI (not modelled).
    DirectSdi,
    /// 10: FIFO mode: the packet handler sends the FIFO.
    Fifo,
    /// 11: PN9 test sequence (no decodable data).
    Pn9,
}

/// Everything the RF side needs, decoded from one register file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModemSettings {
    /// Carrier frequency including hop channel and frequency offset, in Hz (before crystal error).
    pub carrier_hz: f64,
    /// TX bit rate from 0x6E/0x6F/0x70, in bit/s.
    pub tx_bit_rate_bps: f64,
    /// RX bit rate the clock recovery expects (ncoff, ndec, dwn3), in bit/s.
    pub rx_bit_rate_bps: f64,
    /// TX frequency deviation from 0x71/0x72, in Hz.
    pub deviation_hz: f64,
    /// Modulation type.
    pub modulation: Modulation,
    /// TX data source.
    pub data_source: DataSource,
    /// Manchester coding on (doubles the chips per bit).
    pub manchester: bool,
    /// PN9 data whitening on.
    pub whitening: bool,
    /// Approximate receive IF filter bandwidth, in Hz.
    pub if_bandwidth_hz: f64,
    /// AFC pull-in range (±), in Hz; 0 when AFC is off.
    pub afc_pull_in_hz: f64,
    /// Output power selected by 0x6D\[2:0\], in dBm.
    pub tx_power_dbm: f64,
    /// Frequency resolution of this band (156.25 Hz × (hbsel+1)).
    pub step_hz: f64,
}

impl ModemSettings {
    /// Decode the modem registers of `regs`.
    pub fn from_registers(regs: &[u8; 128]) -> Self {
        let r = |a: u8| regs.get(usize::from(a)).copied().unwrap_or(0);
        let hbsel = f64::from((r(0x75) >> 5) & 1);
        let step_hz = 156.25 * (hbsel + 1.0);
        let if_reg = r(0x1C);
        let dwn3 = if_reg >> 7;
        let ndec = (if_reg >> 4) & 0x07;
        let ncoff =
            (u32::from(r(0x21) & 0x0F) << 16) | (u32::from(r(0x22)) << 8) | u32::from(r(0x23));
        // DR_kbps = ncoff · 500 · (1 + 2·dwn3) / 2^(20 + ndec)
        let rx_bit_rate_bps = f64::from(ncoff) * 500_000.0 * (1.0 + 2.0 * f64::from(dwn3))
            / f64::from(1u32 << (20 + u32::from(ndec)));
        let txdr = f64::from(u16::from_be_bytes([r(0x6E), r(0x6F)]));
        let scale = if r(0x70) & 0x20 != 0 {
            2_097_152.0
        } else {
            65_536.0
        };
        let fd = (u16::from(r(0x71) & 0x04) << 6) | u16::from(r(0x72));
        let afc_on = r(0x1D) & 0x40 != 0;
        Self {
            carrier_hz: carrier_hz(regs),
            tx_bit_rate_bps: txdr * 1_000_000.0 / scale,
            rx_bit_rate_bps,
            deviation_hz: f64::from(fd) * 625.0,
            modulation: match r(0x71) & 0x03 {
                0 => Modulation::Unmodulated,
                1 => Modulation::Ook,
                2 => Modulation::Fsk,
                _ => Modulation::Gfsk,
            },
            data_source: match (r(0x71) >> 4) & 0x03 {
                0 => DataSource::DirectGpio,
                1 => DataSource::DirectSdi,
                2 => DataSource::Fifo,
                _ => DataSource::Pn9,
            },
            manchester: r(0x70) & 0x02 != 0,
            whitening: r(0x70) & 0x01 != 0,
            if_bandwidth_hz: if_bandwidth_hz(if_reg),
            afc_pull_in_hz: if afc_on {
                f64::from(r(0x2A)) * (hbsel + 1.0) * 625.0
            } else {
                0.0
            },
            tx_power_dbm: tx_power_dbm(r(0x6D)),
            step_hz,
        }
    }

    /// Carrier offset a receiver with these settings tolerates: the AFC pull-in, or a tenth
    /// of the IF bandwidth without AFC, never more than half the IF bandwidth.
    pub fn frequency_tolerance_hz(&self) -> f64 {
        self.afc_pull_in_hz
            .max(self.if_bandwidth_hz * 0.1)
            .min(self.if_bandwidth_hz * 0.5)
    }

    /// Whether this (receiver) can demodulate `tx`, whose carrier arrives at `tx_carrier_hz`
    /// while ours is at `rx_carrier_hz` (both including crystal error).
    pub fn can_receive(
        &self,
        tx: &ModemSettings,
        tx_carrier_hz: f64,
        rx_carrier_hz: f64,
    ) -> Result<(), Mismatch> {
        let data = |m: Modulation| !matches!(m, Modulation::Unmodulated);
        let fsk = |m: Modulation| matches!(m, Modulation::Fsk | Modulation::Gfsk);
        if !data(tx.modulation)
            || !data(self.modulation)
            || fsk(tx.modulation) != fsk(self.modulation)
        {
            return Err(Mismatch::Modulation);
        }
        if tx.manchester != self.manchester {
            return Err(Mismatch::Modulation);
        }
        let offset_hz = tx_carrier_hz - rx_carrier_hz;
        if offset_hz.abs() > self.frequency_tolerance_hz() {
            return Err(Mismatch::Frequency { offset_hz });
        }
        // Clock recovery locks within a couple of percent of its nominal rate. With
        // Manchester it runs at the chip rate, twice the data rate the sender programs
        // (AN440, "Manchester coding").
        let chips_per_bit = if tx.manchester { 2.0 } else { 1.0 };
        let tx_chip_rate = tx.tx_bit_rate_bps * chips_per_bit;
        let rate_error = (tx_chip_rate - self.rx_bit_rate_bps) / self.rx_bit_rate_bps;
        if !rate_error.is_finite() || rate_error.abs() > 0.02 {
            return Err(Mismatch::BitRate {
                tx_bps: tx_chip_rate,
                rx_bps: self.rx_bit_rate_bps,
            });
        }
        if fsk(tx.modulation) {
            // The signal must fit the filter (Carson: DR + 2Δf, with slack for the
            // approximate filter table) and carry a usable modulation index (h = 2Δf/DR).
            let occupied_hz = tx.tx_bit_rate_bps + 2.0 * tx.deviation_hz;
            let index = 2.0 * tx.deviation_hz / tx.tx_bit_rate_bps;
            if occupied_hz > 1.6 * self.if_bandwidth_hz || index < 0.25 {
                return Err(Mismatch::Deviation {
                    deviation_hz: tx.deviation_hz,
                });
            }
        }
        Ok(())
    }
}

/// Why a receiver cannot demodulate a transmission.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mismatch {
    /// Carrier offset beyond the receiver's tolerance.
    Frequency {
        /// Transmitter minus receiver carrier, in Hz.
        offset_hz: f64,
    },
    /// Bit rates differ by more than 2 %.
    BitRate {
        /// Transmitter bit rate.
        tx_bps: f64,
        /// Receiver clock-recovery bit rate.
        rx_bps: f64,
    },
    /// Deviation does not fit the receiver's filter or is too small to demodulate.
    Deviation {
        /// Transmitter deviation.
        deviation_hz: f64,
    },
    /// Modulation type or Manchester setting differ, or no data modulation.
    Modulation,
}

/// Carrier frequency in Hz: f = (fb + 24 + fc/64000) · 10 MHz · (hbsel + 1) + fhch · fhs · 10 kHz
/// + fo · 156.25 Hz · (hbsel + 1) (datasheet §3.5; the hop term does not scale with hbsel).
pub fn carrier_hz(regs: &[u8; 128]) -> f64 {
    let r = |a: u8| regs.get(usize::from(a)).copied().unwrap_or(0);
    let band = r(0x75);
    let hbsel = f64::from((band >> 5) & 1);
    let fb = f64::from(band & 0x1F);
    let fc = f64::from(u16::from_be_bytes([r(0x76), r(0x77)]));
    let hop_hz = f64::from(r(0x79)) * f64::from(r(0x7A)) * 10_000.0;
    // fo is a 10-bit two's-complement value: 0x74[1:0] are bits 9..8.
    let fo_raw = (u16::from(r(0x74) & 0x03) << 8) | u16::from(r(0x73));
    let fo = if fo_raw & 0x200 != 0 {
        i32::from(fo_raw) - 1024
    } else {
        i32::from(fo_raw)
    };
    (fb + 24.0 + fc / 64_000.0) * 10_000_000.0 * (hbsel + 1.0)
        + hop_hz
        + f64::from(fo) * 156.25 * (hbsel + 1.0)
}

/// TX output power in dBm for 0x6D (txpow\[2:0\]: +1, +2, +5, +8, +11, +14, +17, +20 dBm).
pub fn tx_power_dbm(reg_6d: u8) -> f64 {
    const TABLE_DBM: [f64; 8] = [1.0, 2.0, 5.0, 8.0, 11.0, 14.0, 17.0, 20.0];
    TABLE_DBM
        .get(usize::from(reg_6d & 0x07))
        .copied()
        .unwrap_or(1.0)
}

/// Approximate IF filter bandwidth for 0x1C.
///
/// Exact for the codes the Tau Labs / OpenLRSng tables use. Otherwise:
/// dwn3 = 0, ndec = 0, filset 1..7 = 75.2, 83.2, 90.0, 95.3, 112.1, 127.9, 137.9 kHz;
/// dwn3 = 1, ndec = 0 interpolated between filset 1 = 225.1, 8 = 335.5, 11 = 468.4,
/// 13 = 577.0, 15 = 620.7 kHz; each ndec step halves the bandwidth.
pub fn if_bandwidth_hz(reg_1c: u8) -> f64 {
    const KNOWN_KHZ: [(u8, f64); 8] = [
        (0x01, 75.2),
        (0x05, 112.1),
        (0x06, 127.9),
        (0x95, 167.8),
        (0x81, 225.1),
        (0x88, 335.5),
        (0x8B, 468.4),
        (0x8D, 577.0),
    ];
    if let Some(&(_, khz)) = KNOWN_KHZ.iter().find(|(code, _)| *code == reg_1c) {
        return khz * 1000.0;
    }
    const DIRECT_KHZ: [f64; 16] = [
        75.2, 75.2, 83.2, 90.0, 95.3, 112.1, 127.9, 137.9, 142.8, 148.0, 153.0, 158.0, 163.0,
        168.0, 173.0, 178.0,
    ];
    const DWN3_ANCHORS: [(f64, f64); 5] = [
        (1.0, 225.1),
        (8.0, 335.5),
        (11.0, 468.4),
        (13.0, 577.0),
        (15.0, 620.7),
    ];
    let filset = reg_1c & 0x0F;
    let ndec = (reg_1c >> 4) & 0x07;
    let base_khz = if reg_1c & 0x80 == 0 {
        DIRECT_KHZ.get(usize::from(filset)).copied().unwrap_or(75.2)
    } else {
        let x = f64::from(filset.max(1));
        DWN3_ANCHORS
            .windows(2)
            .find_map(|w| match w {
                [(x0, y0), (x1, y1)] if x <= *x1 => Some(y0 + (y1 - y0) * (x - x0) / (x1 - x0)),
                _ => None,
            })
            .unwrap_or(620.7)
    };
    base_khz * 1000.0 / f64::from(1u32 << ndec)
}

/// Bits on air for a frame: preamble bits plus 8 per byte after it, doubled by Manchester.
pub fn bits_on_air(preamble_bits: u32, bytes_after_preamble: usize, manchester: bool) -> u64 {
    let bits = u64::from(preamble_bits) + 8 * bytes_after_preamble as u64;
    if manchester { 2 * bits } else { bits }
}

/// Airtime in nanoseconds of `bits` at `bit_rate_bps`.
pub fn airtime_ns(bits: u64, bit_rate_bps: f64) -> u64 {
    if bit_rate_bps <= 0.0 {
        return u64::MAX;
    }
    (bits as f64 * 1e9 / bit_rate_bps).round() as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registers::reset_file;

    fn with(pairs: &[(u8, u8)]) -> [u8; 128] {
        let mut regs = reset_file();
        for &(a, v) in pairs {
            regs[usize::from(a)] = v;
        }
        regs
    }

    #[test]
    fn reset_values_decode_to_915_mhz_40_kbps_20_khz() {
        let m = ModemSettings::from_registers(&reset_file());
        assert_eq!(m.carrier_hz, 915_000_000.0);
        assert!(
            (m.tx_bit_rate_bps - 39_993.3).abs() < 0.1,
            "{}",
            m.tx_bit_rate_bps
        );
        assert!(
            (m.rx_bit_rate_bps - 40_000.0).abs() < 1.0,
            "{}",
            m.rx_bit_rate_bps
        );
        assert_eq!(m.deviation_hz, 20_000.0);
        assert_eq!(m.modulation, Modulation::Unmodulated);
        assert_eq!(m.tx_power_dbm, 1.0);
    }

    #[test]
    fn carrier_430_mhz_with_hop_and_offset() {
        // 0x75 = 0x53: sbsel, hbsel 0, fb 19 → (19 + 24) · 10 MHz = 430 MHz.
        let regs = with(&[(0x75, 0x53), (0x76, 0), (0x77, 0), (0x79, 10), (0x7A, 4)]);
        assert_eq!(carrier_hz(&regs), 430_400_000.0);
        // fo = -2 (0x3FE) → -312.5 Hz.
        let regs = with(&[
            (0x75, 0x53),
            (0x76, 0),
            (0x77, 0),
            (0x73, 0xFE),
            (0x74, 0x03),
        ]);
        assert_eq!(carrier_hz(&regs), 430_000_000.0 - 312.5);
        // 868 band: fb 19, hbsel 1, fc 25600 → (43 + 0.4) · 20 MHz = 868 MHz.
        let regs = with(&[(0x75, 0x73), (0x76, 0x64), (0x77, 0x00)]);
        assert_eq!(carrier_hz(&regs), 868_000_000.0);
    }

    #[test]
    fn tau_labs_57600_profile() {
        let regs = with(&[
            (0x1C, 0x95),
            (0x1D, 0x40),
            (0x20, 0x68),
            (0x21, 0x01),
            (0x22, 0x3A),
            (0x23, 0x93),
            (0x2A, 0x3C),
            (0x6E, 0x0E),
            (0x6F, 0xBF),
            (0x70, 0x0C),
            (0x71, 0x23),
            (0x72, 0x48),
            (0x75, 0x53),
        ]);
        let m = ModemSettings::from_registers(&regs);
        assert!(
            (m.tx_bit_rate_bps - 57_601.9).abs() < 0.1,
            "{}",
            m.tx_bit_rate_bps
        );
        assert!(
            (m.rx_bit_rate_bps - 57_600.0).abs() < 1.0,
            "{}",
            m.rx_bit_rate_bps
        );
        assert_eq!(m.deviation_hz, 45_000.0);
        assert!(
            (m.if_bandwidth_hz - 167_800.0).abs() < 1_000.0,
            "{}",
            m.if_bandwidth_hz
        );
        assert_eq!(m.afc_pull_in_hz, 37_500.0);
        assert_eq!(m.modulation, Modulation::Gfsk);
        assert_eq!(m.data_source, DataSource::Fifo);
        assert!(m.can_receive(&m, 430e6, 430e6).is_ok());
        assert!(m.can_receive(&m, 430e6 + 30e3, 430e6).is_ok());
        assert!(matches!(
            m.can_receive(&m, 430.04e6, 430e6),
            Err(Mismatch::Frequency { .. })
        ));
    }

    #[test]
    fn if_filter_anchors_match_radio_md() {
        for (code, khz) in [
            (0x01, 75.2),
            (0x05, 112.1),
            (0x06, 127.9),
            (0x81, 225.1),
            (0x88, 335.5),
            (0x8B, 468.4),
            (0x8D, 577.0),
        ] {
            assert!(
                (if_bandwidth_hz(code) / 1000.0 - khz).abs() < 0.05,
                "{code:#x}"
            );
        }
        assert!((if_bandwidth_hz(0x95) / 1000.0 - 167.8).abs() < 1.0);
    }

    #[test]
    fn airtime_of_a_tau_labs_frame() {
        // 6 B preamble, 4 B sync, 4 B header, 1 B length, 16 B payload at 57 600 bit/s.
        let bits = bits_on_air(48, 4 + 4 + 1 + 16, false);
        assert_eq!(bits, 248);
        assert_eq!(airtime_ns(bits, 57_600.0), 4_305_556);
        assert_eq!(bits_on_air(48, 25, true), 496);
    }
}
