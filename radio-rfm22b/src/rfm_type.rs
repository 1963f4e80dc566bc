//! The RFM22B module variants (433, 868, 915 MHz) and the frequency range each is used over
//! (OpenLRSng `binding.h`: `RFMTYPE`, `MIN_RFM_FREQUENCY`, `MAX_RFM_FREQUENCY`,
//! `DEFAULT_CARRIER_FREQUENCY`, `BINDING_FREQUENCY`).

/// The RFM22B module variant: the band its RF matching is built for, and the frequency
/// range OpenLRSng uses it over (OpenLRSng's `RFMTYPE`). Not a band plan: the link's plans
/// (`telemetry::link::Band`, including the 433 MHz ISM sub-band) each run on one variant,
/// `RfmType::for_band`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RfmType {
    /// 433 MHz modules (413–463 MHz).
    Mhz433,
    /// 868 MHz modules (848–888 MHz).
    Mhz868,
    /// 915 MHz modules (895–935 MHz).
    Mhz915,
}

impl RfmType {
    /// `BINDING_FREQUENCY`: where bind packets are exchanged.
    pub const fn binding_frequency_hz(self) -> u32 {
        self.default_carrier_frequency_hz()
    }

    /// `DEFAULT_CARRIER_FREQUENCY`: channel 0 of fresh bind data.
    pub const fn default_carrier_frequency_hz(self) -> u32 {
        match self {
            Self::Mhz433 => 435_000_000,
            Self::Mhz868 => 868_000_000,
            Self::Mhz915 => 915_000_000,
        }
    }

    /// `MIN_RFM_FREQUENCY`, the lowest frequency the module is used at.
    pub const fn min_frequency_hz(self) -> u32 {
        match self {
            Self::Mhz433 => 413_000_000,
            Self::Mhz868 => 848_000_000,
            Self::Mhz915 => 895_000_000,
        }
    }

    /// `MAX_RFM_FREQUENCY`: also the TX's default `max_frequency` for random hop channels.
    pub const fn max_frequency_hz(self) -> u32 {
        match self {
            Self::Mhz433 => 463_000_000,
            Self::Mhz868 => 888_000_000,
            Self::Mhz915 => 935_000_000,
        }
    }

    /// Whether `frequency_hz` lies in this band's plan (`MIN_RFM_FREQUENCY..=MAX_RFM_FREQUENCY`).
    pub const fn contains(self, frequency_hz: u64) -> bool {
        frequency_hz >= self.min_frequency_hz() as u64
            && frequency_hz <= self.max_frequency_hz() as u64
    }

    /// The band whose plan holds `frequency_hz` (the three plans do not overlap).
    pub const fn containing(frequency_hz: u64) -> Option<Self> {
        if Self::Mhz433.contains(frequency_hz) {
            Some(Self::Mhz433)
        } else if Self::Mhz868.contains(frequency_hz) {
            Some(Self::Mhz868)
        } else if Self::Mhz915.contains(frequency_hz) {
            Some(Self::Mhz915)
        } else {
            None
        }
    }

    /// The band for an `RFMTYPE` number (433, 868, 915).
    pub const fn from_rfm_type(rfm_type: u16) -> Option<Self> {
        match rfm_type {
            433 => Some(Self::Mhz433),
            868 => Some(Self::Mhz868),
            915 => Some(Self::Mhz915),
            _ => None,
        }
    }
}

#[cfg(feature = "telemetry")]
impl RfmType {
    /// The module variant a link band plan runs on (the 433 MHz ISM sub-band on the 433 MHz
    /// module).
    pub const fn for_band(band: telemetry::link::Band) -> Self {
        use telemetry::link::Band;
        match band {
            Band::Mhz433 | Band::Ism433 => Self::Mhz433,
            Band::Mhz868 => Self::Mhz868,
            Band::Mhz915 => Self::Mhz915,
        }
    }
}
