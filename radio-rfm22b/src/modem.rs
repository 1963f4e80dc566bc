//! Modem configuration, computed: bit rate, deviation and modulation in; the 18 modem
//! registers (0x1C–0x25, 0x2A, 0x58, 0x69, 0x6E–0x72) out, the way Silicon Labs' register
//! calculator derives them (datasheet "Modulation Options" and register descriptions, AN440). Pure and `const`.
//!
//! The calculator is a spreadsheet whose outputs also depend on choices it makes from
//! lookup tables. Those are encoded here from the datasheet (IF filter table, see
//! [`IfFilter`]) and from the values the calculator produced for the Tau Labs and OpenLRSng
//! tables (AFC limiter, AFC timing, charge pump); `tests/modem_math.rs` checks every row of
//! both tables.

use crate::ConfigError;
use crate::if_filter::IfFilter;

mod settings;
pub use settings::ModemSettings;

/// Frequency-shift keying flavour (0x71 modtyp).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Modulation {
    /// Gaussian FSK (BT = 0.5); what Tau Labs and OpenLRSng use.
    Gfsk,
    /// Plain 2-FSK.
    Fsk,
}

/// The computed modem registers, in address order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModemRegisters {
    /// 0x1C–0x25: IF filter, AFC gearshift, AFC timing, clock-recovery gearshift,
    /// rxosr, ncoff, crgain.
    pub block_1c: [u8; 10],
    /// 0x2A AFC limiter.
    pub afc_limiter: u8,
    /// 0x58 charge-pump trim.
    pub charge_pump: u8,
    /// 0x69 AGC override.
    pub agc: u8,
    /// 0x6E–0x72: TX data rate, modulation control 1/2, deviation.
    pub block_6e: [u8; 5],
}

impl ModemRegisters {
    /// Every register as `(address, value)`, in address order.
    pub const fn writes(&self) -> [(u8, u8); 18] {
        let b = self.block_1c;
        let t = self.block_6e;
        [
            (0x1C, b[0]),
            (0x1D, b[1]),
            (0x1E, b[2]),
            (0x1F, b[3]),
            (0x20, b[4]),
            (0x21, b[5]),
            (0x22, b[6]),
            (0x23, b[7]),
            (0x24, b[8]),
            (0x25, b[9]),
            (0x2A, self.afc_limiter),
            (0x58, self.charge_pump),
            (0x69, self.agc),
            (0x6E, t[0]),
            (0x6F, t[1]),
            (0x70, t[2]),
            (0x71, t[3]),
            (0x72, t[4]),
        ]
    }
}

/// A validated modem configuration and its registers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModemConfig {
    settings: ModemSettings,
    filter: IfFilter,
    registers: ModemRegisters,
}

/// Below this rate the TX data rate uses the fine scale (0x70 txdtrtscale, datasheet "Data Rate").
const TX_FINE_SCALE_BELOW_BPS: u32 = 30_000;

/// `round(num / den)`, halves up, as the calculator's `ROUND`.
const fn div_round(num: u64, den: u64) -> u64 {
    (2 * num + den) / (2 * den)
}

impl ModemConfig {
    /// GFSK at `bit_rate_bps` with `deviation_hz` and the calculator's choices.
    ///
    /// # Panics
    /// On an invalid setting. Meant for `const` items, where that is a compile error; use
    /// [`ModemConfig::try_new`] for values known only at run time.
    #[allow(clippy::panic)] // const-evaluation guard, documented above
    pub const fn new(bit_rate_bps: u32, deviation_hz: u32) -> Self {
        match Self::try_new(bit_rate_bps, deviation_hz) {
            Ok(config) => config,
            Err(_) => panic!("invalid modem configuration"),
        }
    }

    /// GFSK at `bit_rate_bps` with `deviation_hz`; a typed error if the chip cannot do it.
    pub const fn try_new(bit_rate_bps: u32, deviation_hz: u32) -> Result<Self, ConfigError> {
        Self::try_from_settings(ModemSettings::new(bit_rate_bps, deviation_hz))
    }

    /// Like [`ModemConfig::new`] for full settings.
    ///
    /// # Panics
    /// On an invalid setting (meant for `const` items, see [`ModemConfig::new`]).
    #[allow(clippy::panic)] // const-evaluation guard, documented above
    pub const fn from_settings(settings: ModemSettings) -> Self {
        match Self::try_from_settings(settings) {
            Ok(config) => config,
            Err(_) => panic!("invalid modem configuration"),
        }
    }

    /// Computes the registers for `settings`.
    pub const fn try_from_settings(settings: ModemSettings) -> Result<Self, ConfigError> {
        let bit_rate = settings.bit_rate_bps;
        if bit_rate < 1_000 || bit_rate > 256_000 {
            return Err(ConfigError::BitRateOutOfRange);
        }
        // fd is 9 bits of 625 Hz (datasheet "Frequency Deviation": Δf = fd · 625 Hz).
        let fd = div_round(settings.deviation_hz as u64, 625);
        if fd == 0 || fd > 0x1FF || settings.rx_deviation_hz < 625 {
            return Err(ConfigError::DeviationOutOfRange);
        }
        // The receiver sees twice the rate with Manchester (AN440: "Rb·(1+enmanch)").
        let chip_rate = bit_rate as u64 * if settings.manchester { 2 } else { 1 };
        let rx_deviation = settings.rx_deviation_hz as u64;
        // Carson's rule, as the calculator: BW = Rb + 2·Δf.
        let wanted_bandwidth = chip_rate + 2 * rx_deviation;
        let filter = match settings.if_filter {
            Some(filter) => filter,
            None => match IfFilter::for_bandwidth_hz(wanted_bandwidth as u32) {
                Some(filter) => filter,
                None => return Err(ConfigError::BandwidthTooWide),
            },
        };
        let ndec = filter.ndec_exp() as u32;
        let dwn3: u64 = if filter.dwn3_bypass() { 3 } else { 1 };
        // AN440 eq. 3: rxosr = 500 kHz·(1+2·dwn3_bypass) / (2^(ndec_exp−3) · Rb).
        let rxosr = div_round(4_000_000 * dwn3, chip_rate << ndec);
        // AN440 eq. 4: ncoff = Rb · 2^(20+ndec_exp) / (500 kHz·(1+2·dwn3_bypass)).
        let ncoff = div_round(chip_rate << (20 + ndec), 500_000 * dwn3);
        if rxosr == 0 || rxosr > 0x7FF || ncoff > 0xF_FFFF {
            return Err(ConfigError::ClockRecoveryOutOfRange);
        }
        // AN440 eq. 5: crgain = 2 + 2^16 · Rb / (rxosr · Δf), saturating at 11 bits.
        let crgain = 2 + div_round(65_536 * chip_rate, rxosr * rx_deviation);
        let crgain = if crgain > 0x7FF { 0x7FF } else { crgain };

        let fine_scale = bit_rate < TX_FINE_SCALE_BELOW_BPS;
        // Datasheet "Data Rate": DR = txdr · 1 MHz / 2^(16 + 5·txdtrtscale).
        let txdr = if fine_scale {
            div_round((bit_rate as u64) << 21, 1_000_000)
        } else {
            div_round((bit_rate as u64) << 16, 1_000_000)
        };
        let reg_70 = (if fine_scale { 0x20 } else { 0 })
            | (if settings.manchester_inverted {
                0x0C
            } else {
                0
            })
            | (if settings.manchester { 0x02 } else { 0 });
        let modtyp = match settings.modulation {
            Modulation::Gfsk => 0x03,
            Modulation::Fsk => 0x02,
        };
        // 0x71: dtmod = FIFO mode (0b10 << 4), fd[8] in bit 2, modtyp in bits 1:0.
        let reg_71 = 0x20 | (((fd >> 8) as u8) << 2) | modtyp;

        let afc_limiter = match settings.afc_limiter {
            Some(limiter) => limiter,
            None => auto_afc_limiter(filter, wanted_bandwidth as u32),
        };
        let registers = ModemRegisters {
            block_1c: [
                filter.register(),
                if settings.afc { 0x40 } else { 0x00 },
                // AFC timing: the calculator shortens the AFC wait (anwait) at the top rate.
                if bit_rate > 200_000 { 0x02 } else { 0x0A },
                0x03, // clock-recovery gearshift: the reset value, written for completeness
                rxosr as u8,
                (((rxosr >> 8) as u8) << 5) | ((ncoff >> 16) as u8 & 0x0F),
                (ncoff >> 8) as u8,
                ncoff as u8,
                (crgain >> 8) as u8,
                crgain as u8,
            ],
            afc_limiter,
            // Charge-pump trim: the calculator raises it from 100 kbps and again at 256k.
            charge_pump: if bit_rate < 100_000 {
                0x80
            } else if bit_rate <= 200_000 {
                0xC0
            } else {
                0xED
            },
            agc: 0x60, // AGC on, gain increase allowed (the calculator's constant)
            block_6e: [(txdr >> 8) as u8, txdr as u8, reg_70, reg_71, fd as u8],
        };
        Ok(Self {
            settings,
            filter,
            registers,
        })
    }

    /// The settings this was computed from.
    pub const fn settings(&self) -> &ModemSettings {
        &self.settings
    }

    /// The IF filter in use.
    pub const fn if_filter(&self) -> IfFilter {
        self.filter
    }

    /// The register values.
    pub const fn registers(&self) -> &ModemRegisters {
        &self.registers
    }

    /// The air bit rate.
    pub const fn bit_rate_bps(&self) -> u32 {
        self.settings.bit_rate_bps
    }

    /// The deviation actually programmed (fd · 625 Hz).
    pub const fn deviation_hz(&self) -> u32 {
        let [.., fd_low] = self.registers.block_6e;
        let fd8 = (self.registers.block_6e[3] >> 2) & 1;
        (((fd8 as u32) << 8) | fd_low as u32) * 625
    }
}

/// The calculator's AFC limiter (0x2A; pull-in = limiter · 625 Hz · (hbsel+1)). It follows
/// the channel filter: both captured tables give 30 at 75.2 kHz, 36 at 112.1 kHz, 40 at
/// 127.9 kHz, 60 at 167.8 kHz and 80 from 225.1 kHz. Narrower filters keep the 75.2 kHz
/// ratio (pull-in ≈ bandwidth / 4).
const fn auto_afc_limiter(filter: IfFilter, wanted_bandwidth_hz: u32) -> u8 {
    let bandwidth = match filter.bandwidth_hz() {
        Some(bandwidth) => bandwidth,
        None => wanted_bandwidth_hz,
    };
    if bandwidth <= 75_200 {
        let limiter = bandwidth / 2_500;
        if limiter == 0 { 1 } else { limiter as u8 }
    } else if bandwidth <= 112_100 {
        0x24
    } else if bandwidth <= 137_900 {
        0x28
    } else if bandwidth <= 167_800 {
        0x3C
    } else {
        0x50
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn const_construction_works() {
        const M: ModemConfig = ModemConfig::new(57_600, 45_000);
        assert_eq!(M.registers().block_1c[0], 0x95);
        assert_eq!(M.deviation_hz(), 45_000);
    }

    #[test]
    fn invalid_settings_are_typed_errors() {
        assert_eq!(
            ModemConfig::try_new(999, 5_000),
            Err(ConfigError::BitRateOutOfRange)
        );
        assert_eq!(
            ModemConfig::try_new(256_001, 5_000),
            Err(ConfigError::BitRateOutOfRange)
        );
        assert_eq!(
            ModemConfig::try_new(9_600, 0),
            Err(ConfigError::DeviationOutOfRange)
        );
        assert_eq!(
            ModemConfig::try_new(9_600, 320_000),
            Err(ConfigError::DeviationOutOfRange)
        );
        assert_eq!(
            ModemConfig::try_new(256_000, 200_000),
            Err(ConfigError::BandwidthTooWide)
        );
        // 1 kbps through the widest decimation-free filter: rxosr = 4000 > 2047.
        let wide = ModemSettings::new(1_000, 5_000)
            .with_if_filter(IfFilter::for_bandwidth_hz(600_000).unwrap());
        assert_eq!(
            ModemConfig::try_from_settings(wide),
            Err(ConfigError::ClockRecoveryOutOfRange)
        );
    }

    #[test]
    fn fsk_manchester_and_afc_switches() {
        let gfsk = ModemConfig::new(9_600, 30_000);
        let fsk = ModemConfig::from_settings(
            ModemSettings::new(9_600, 30_000).with_modulation(Modulation::Fsk),
        );
        assert_eq!(gfsk.registers().block_6e[3], 0x23);
        assert_eq!(fsk.registers().block_6e[3], 0x22);
        // Manchester: the receiver sees 19.2 kchip/s, so rxosr halves (417 → 208) and the
        // filter must pass 19.2 + 60 = 79.2 kHz (0x02, 83.2 kHz, instead of 0x01).
        let manchester =
            ModemConfig::from_settings(ModemSettings::new(9_600, 30_000).with_manchester(true));
        let r = manchester.registers();
        assert_eq!(r.block_1c[0], 0x02);
        assert_eq!(r.block_1c[4], 208);
        assert_eq!(r.block_6e[2] & 0x02, 0x02);
        // TX rate is the bit rate, not the chip rate.
        assert_eq!(r.block_6e[..2], gfsk.registers().block_6e[..2]);
        // AFC off clears 0x1D.
        let no_afc = ModemConfig::from_settings(ModemSettings::new(9_600, 30_000).with_afc(false));
        assert_eq!(no_afc.registers().block_1c[1], 0x00);
        // A deviation above 159.375 kHz sets fd[8] in 0x71.
        let wide = ModemConfig::new(100_000, 200_000);
        assert_eq!(wide.registers().block_6e[3], 0x27);
        assert_eq!(wide.registers().block_6e[4], 0x40);
        assert_eq!(wide.deviation_hz(), 200_000);
    }

    #[test]
    fn whole_range_computes() {
        // Every rate from 1 to 256 kbps with a deviation of half the rate (min 2.5 kHz).
        let mut rate = 1_000;
        while rate <= 256_000 {
            let deviation = (rate / 2).max(2_500);
            let m = ModemConfig::try_new(rate, deviation).unwrap();
            let r = m.registers();
            let rxosr = u32::from(r.block_1c[4]) | (u32::from(r.block_1c[5] >> 5) << 8);
            assert!((8..=2047).contains(&rxosr), "rate {rate}: rxosr {rxosr}");
            // The programmed TX rate is within 0.05 % of the asked one (datasheet "Data Rate").
            let txdr = f64::from(u16::from_be_bytes([r.block_6e[0], r.block_6e[1]]));
            let scale = if r.block_6e[2] & 0x20 != 0 {
                2f64.powi(21)
            } else {
                2f64.powi(16)
            };
            let actual = txdr * 1e6 / scale;
            let error = (actual - f64::from(rate)).abs() / f64::from(rate);
            assert!(error < 5e-4, "rate {rate}: programmed {actual:.1} bps");
            // The clock-recovery NCO reproduces the rate: Rb = ncoff·500 kHz·(1+2·dwn3)/2^(20+ndec).
            let ncoff = (u32::from(r.block_1c[5] & 0x0F) << 16)
                | (u32::from(r.block_1c[6]) << 8)
                | u32::from(r.block_1c[7]);
            let f = m.if_filter();
            let dwn3 = if f.dwn3_bypass() { 3.0 } else { 1.0 };
            let rx_rate = f64::from(ncoff) * 500e3 * dwn3 / 2f64.powi(20 + i32::from(f.ndec_exp()));
            assert!(
                (rx_rate - f64::from(rate)).abs() / f64::from(rate) < 1e-3,
                "rate {rate}: NCO {rx_rate:.1}"
            );
            rate += 1_000;
        }
    }
}
