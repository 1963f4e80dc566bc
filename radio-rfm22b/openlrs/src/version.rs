//! OpenLRSng firmware generations and RF bands: the binding version, the bind magic and the
//! per-band frequency limits (OpenLRSng `binding.h`).

/// Which OpenLRSng generation we speak to. 3.8 and 3.9 refuse each other at bind time and at
/// every packet afterwards (the bind magic differs), so this must match the other end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BindingVersion {
    /// Releases 3.8.x (`OPENLRSNG_VERSION` 0x0388), dRonin and Tau Labs `pios_openlrs`.
    V38,
    /// Master 3.9.0 (`OPENLRSNG_VERSION` 0x0390).
    V39,
}

impl BindingVersion {
    /// The `OPENLRSNG_VERSION` constant the vectors were generated with.
    pub const fn openlrsng_version(self) -> u16 {
        match self {
            Self::V38 => 0x0388,
            Self::V39 => 0x0390,
        }
    }

    /// `BINDING_VERSION = (ver & 0x0FF0) >> 4`, byte 0 of the bind data.
    pub const fn byte(self) -> u8 {
        // The mask keeps 8 bits, so the cast is lossless.
        ((self.openlrsng_version() & 0x0FF0) >> 4) as u8
    }

    /// Looks a binding-version byte up; `None` for versions we do not speak.
    pub const fn from_byte(byte: u8) -> Option<Self> {
        match byte {
            0x38 => Some(Self::V38),
            0x39 => Some(Self::V39),
            _ => None,
        }
    }

    /// `BIND_MAGIC = 0xDEC1BE15 + (ver & 0xFFF0)`: the 4-byte header used while binding.
    pub const fn bind_magic(self) -> u32 {
        0xDEC1_BE15 + (self.openlrsng_version() as u32 & 0xFFF0)
    }
}

/// The RFM22B band variant an OpenLRSng image was built for (`RFMTYPE`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Band {
    /// 433 MHz modules (413–463 MHz).
    Mhz433,
    /// 868 MHz modules (848–888 MHz).
    Mhz868,
    /// 915 MHz modules (895–935 MHz).
    Mhz915,
}

impl Band {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magic_and_version_bytes_match_the_reference_table() {
        assert_eq!(BindingVersion::V38.byte(), 0x38);
        assert_eq!(BindingVersion::V39.byte(), 0x39);
        assert_eq!(BindingVersion::V38.bind_magic(), 0xDEC1_C195);
        assert_eq!(BindingVersion::V39.bind_magic(), 0xDEC1_C1A5);
        assert_eq!(BindingVersion::from_byte(0x39), Some(BindingVersion::V39));
        assert_eq!(BindingVersion::from_byte(0x37), None);
    }
}
