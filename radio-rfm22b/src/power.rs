//! Transmit power (0x6D; datasheet "Output Power Selection") and crystal load capacitance (0x09; "Crystal Oscillator"). Pure.

use crate::ConfigError;

/// The eight output levels of the Si4432 / RFM22B (0x6D `txpow[2:0]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TxPower(u8);

/// dBm of each txpow step (+1, +2, +5, +8, +11, +14, +17, +20 dBm).
const STEPS_DBM: [i8; 8] = [1, 2, 5, 8, 11, 14, 17, 20];

impl TxPower {
    /// +20 dBm (100 mW).
    pub const MAX: Self = Self(7);
    /// +1 dBm (1.25 mW).
    pub const MIN: Self = Self(0);

    /// The highest step not above `dbm` (1–20 dBm; e.g. 10 dBm → +8 dBm).
    pub const fn try_from_dbm(dbm: i8) -> Result<Self, ConfigError> {
        if dbm < 1 || dbm > 20 {
            return Err(ConfigError::TxPowerOutOfRange);
        }
        // The last step whose level does not exceed `dbm`.
        let mut step = 0;
        let mut rest: &[i8] = &STEPS_DBM;
        let mut index = 0;
        while let [level, tail @ ..] = rest {
            if *level <= dbm {
                step = index;
            }
            index += 1;
            rest = tail;
        }
        Ok(Self(step))
    }

    /// The raw txpow step 0–7 (values above 7 saturate).
    pub const fn from_step(step: u8) -> Self {
        Self(if step > 7 { 7 } else { step })
    }

    /// The txpow step 0–7.
    pub const fn step(self) -> u8 {
        self.0
    }

    /// The nominal output in dBm.
    pub const fn dbm(self) -> i8 {
        match self.0 {
            0 => 1,
            1 => 2,
            2 => 5,
            3 => 8,
            4 => 11,
            5 => 14,
            6 => 17,
            _ => 20,
        }
    }

    /// Register 0x6D, with `lna_sw` (bit 3) for modules whose LNA switch the chip drives.
    pub const fn register(self, lna_switch: bool) -> u8 {
        (if lna_switch { 0x08 } else { 0 }) | self.0
    }
}

/// Crystal load capacitance trim (0x09): C ≈ 1.8 pF + 0.085 pF · xlc + 3.7 pF · xtalshft.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CrystalLoad(u8);

impl CrystalLoad {
    /// 0x7F, what every Tau Labs, OpenLRSng and dRonin board uses (≈ 12.6 pF).
    pub const RFM22B: Self = Self(0x7F);

    /// A raw 0x09 value (bit 7 xtalshft, bits 6:0 xlc).
    pub const fn from_register(value: u8) -> Self {
        Self(value)
    }

    /// Register 0x09.
    pub const fn register(self) -> u8 {
        self.0
    }

    /// The resulting load capacitance in femtofarads.
    pub const fn capacitance_ff(self) -> u32 {
        1_800 + 85 * (self.0 & 0x7F) as u32 + if self.0 & 0x80 != 0 { 3_700 } else { 0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dbm_to_steps() {
        assert_eq!(TxPower::try_from_dbm(20).unwrap().step(), 7);
        assert_eq!(TxPower::try_from_dbm(19).unwrap().step(), 6);
        assert_eq!(TxPower::try_from_dbm(10).unwrap().dbm(), 8);
        assert_eq!(TxPower::try_from_dbm(1).unwrap().step(), 0);
        assert_eq!(
            TxPower::try_from_dbm(0),
            Err(ConfigError::TxPowerOutOfRange)
        );
        assert_eq!(
            TxPower::try_from_dbm(21),
            Err(ConfigError::TxPowerOutOfRange)
        );
        // Tau Labs writes 0x08 | txpow; OpenLRSng (rfmSetPower(5)) the bare step.
        assert_eq!(TxPower::from_step(5).register(false), 0x05);
        assert_eq!(TxPower::MAX.register(true), 0x0F);
        assert_eq!(TxPower::from_step(9), TxPower::MAX);
    }

    #[test]
    fn crystal_load() {
        assert_eq!(CrystalLoad::RFM22B.capacitance_ff(), 12_595);
        assert_eq!(CrystalLoad::from_register(0x80).capacitance_ff(), 5_500);
    }
}
