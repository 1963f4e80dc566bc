//! Carrier frequency and frequency hopping (registers 0x75–0x77, 0x79, 0x7A; datasheet
//! "Frequency Control"): f = (fb + 24 + fc/64000) · 10 MHz · (hbsel+1) + fhch · fhs · 10 kHz. Pure, `const`.

use crate::ConfigError;

/// Lowest carrier the synthesizer covers.
pub const MIN_FREQUENCY_HZ: u32 = 240_000_000;
/// Upper limit (exclusive): fb is 5 bits, so 960 MHz itself is not representable.
pub const MAX_FREQUENCY_HZ: u32 = 960_000_000;
/// Above this the high band (hbsel = 1) is used.
const HIGH_BAND_FROM_HZ: u32 = 480_000_000;

/// A nominal carrier: band select and fc (hop channel 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Carrier {
    frequency_hz: u32,
    band_select: u8,
    fc: u16,
}

impl Carrier {
    /// The carrier for `frequency_hz`.
    ///
    /// # Panics
    /// Outside 240–960 MHz (meant for `const` items; use [`Carrier::try_new`] at run time).
    #[allow(clippy::panic)] // const-evaluation guard, documented above
    pub const fn new(frequency_hz: u32) -> Self {
        match Self::try_new(frequency_hz) {
            Ok(carrier) => carrier,
            Err(_) => panic!("carrier outside 240-960 MHz"),
        }
    }

    /// The carrier for `frequency_hz`, with the integer arithmetic of OpenLRSng's
    /// `rfmSetCarrierFrequency` (exact for every 156.25/312.5 Hz step; truncates between).
    pub const fn try_new(frequency_hz: u32) -> Result<Self, ConfigError> {
        if frequency_hz < MIN_FREQUENCY_HZ || frequency_hz >= MAX_FREQUENCY_HZ {
            return Err(ConfigError::FrequencyOutOfRange);
        }
        let high = frequency_hz >= HIGH_BAND_FROM_HZ;
        // Band width is 10 MHz (low) or 20 MHz (high); fc counts 64000 steps of it.
        let band_hz = if high { 20_000_000 } else { 10_000_000 };
        let fb = frequency_hz / band_hz - 24;
        let remainder = frequency_hz - (fb + 24) * band_hz;
        // remainder · 64000 / band = remainder · 4/625 (low) or · 2/625 (high).
        let fc = if high {
            remainder * 2 / 625
        } else {
            remainder * 4 / 625
        };
        Ok(Self {
            frequency_hz,
            // 0x75: sbsel (bit 6, always set) | hbsel (bit 5) | fb[4:0].
            band_select: 0x40 | (if high { 0x20 } else { 0 }) | fb as u8,
            fc: fc as u16,
        })
    }

    /// The requested frequency.
    pub const fn frequency_hz(&self) -> u32 {
        self.frequency_hz
    }

    /// Registers 0x75, 0x76, 0x77.
    pub const fn registers(&self) -> [u8; 3] {
        let [high, low] = self.fc.to_be_bytes();
        [self.band_select, high, low]
    }

    /// True in the 480–960 MHz band (hbsel = 1).
    pub const fn high_band(&self) -> bool {
        self.band_select & 0x20 != 0
    }

    /// The AFC correction step: 156.25 Hz · (hbsel+1), in millihertz.
    pub const fn afc_step_millihertz(&self) -> i32 {
        if self.high_band() { 312_500 } else { 156_250 }
    }
}

/// Channel spacing for hopping (0x7A, in 10 kHz steps, independent of hbsel).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelSpacing(u8);

impl ChannelSpacing {
    /// `steps` × 10 kHz (0 disables hopping offsets).
    pub const fn from_10khz_steps(steps: u8) -> Self {
        Self(steps)
    }

    /// The nearest representable spacing to `spacing_hz` (up to 2.55 MHz).
    pub const fn try_from_hz(spacing_hz: u32) -> Result<Self, ConfigError> {
        let steps = (spacing_hz + 5_000) / 10_000;
        if steps > 255 {
            return Err(ConfigError::FrequencyOutOfRange);
        }
        Ok(Self(steps as u8))
    }

    /// Register 0x7A.
    pub const fn register(self) -> u8 {
        self.0
    }

    /// The spacing in Hz.
    pub const fn spacing_hz(self) -> u32 {
        self.0 as u32 * 10_000
    }
}

/// The frequency of hop `channel` (0x79) on `carrier` with `spacing`.
pub const fn channel_frequency_hz(carrier: &Carrier, spacing: ChannelSpacing, channel: u8) -> u32 {
    carrier.frequency_hz() + channel as u32 * spacing.spacing_hz()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_and_edges() {
        assert_eq!(Carrier::new(430_000_000).registers(), [0x53, 0x00, 0x00]);
        assert_eq!(Carrier::new(240_000_000).registers(), [0x40, 0x00, 0x00]);
        // 862 MHz: Tau Labs' float code gives fc 6399; the integer form gives the exact 6400.
        assert_eq!(Carrier::new(862_000_000).registers(), [0x73, 0x19, 0x00]);
        assert!(!Carrier::new(479_999_999).high_band());
        assert!(Carrier::new(480_000_000).high_band());
        assert_eq!(
            Carrier::try_new(239_999_999),
            Err(ConfigError::FrequencyOutOfRange)
        );
        assert_eq!(
            Carrier::try_new(960_000_000),
            Err(ConfigError::FrequencyOutOfRange)
        );
    }

    #[test]
    fn hop_channels_do_not_scale_with_band() {
        // The datasheet's 900 MHz example: 1 MHz step × channel 5 = 905 MHz.
        let spacing = ChannelSpacing::try_from_hz(1_000_000).unwrap();
        assert_eq!(spacing.register(), 100);
        assert_eq!(
            channel_frequency_hz(&Carrier::new(900_000_000), spacing, 5),
            905_000_000
        );
        assert_eq!(Carrier::new(900_000_000).afc_step_millihertz(), 312_500);
        assert_eq!(Carrier::new(433_000_000).afc_step_millihertz(), 156_250);
    }
}
