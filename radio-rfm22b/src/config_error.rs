//! Why a configuration was refused. Raised once, at construction (usually in `const`), never
//! while the radio runs.

/// An invalid modem, carrier, packet or power setting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// The bit rate is outside 1–256 kbps.
    BitRateOutOfRange,
    /// The deviation is outside 625 Hz – 319.375 kHz (9-bit fd in 625 Hz steps).
    DeviationOutOfRange,
    /// Bit rate + 2 × deviation is wider than the widest IF filter (620.7 kHz).
    BandwidthTooWide,
    /// An IF filter register value with filset 0 or ndec_exp > 5.
    InvalidIfFilter,
    /// The clock-recovery oversampling ratio or NCO offset does not fit its register.
    ClockRecoveryOutOfRange,
    /// The carrier is outside 240–960 MHz.
    FrequencyOutOfRange,
    /// The preamble is outside 1–511 nibbles or the detection threshold outside 1–31 nibbles.
    InvalidPreamble,
    /// The sync word is not 1–4 bytes.
    InvalidSyncWord,
    /// The header is longer than 4 bytes, or a checked byte is not sent.
    InvalidHeader,
    /// A fixed packet length of 0.
    InvalidLength,
    /// The TX power is outside 1–20 dBm.
    TxPowerOutOfRange,
    /// A FIFO threshold outside 1–63 bytes.
    InvalidFifoThreshold,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let text = match self {
            ConfigError::BitRateOutOfRange => "bit rate outside 1-256 kbps",
            ConfigError::DeviationOutOfRange => "deviation outside 625 Hz - 319.375 kHz",
            ConfigError::BandwidthTooWide => "bit rate + 2 x deviation exceeds 620.7 kHz",
            ConfigError::InvalidIfFilter => "invalid IF filter register value",
            ConfigError::ClockRecoveryOutOfRange => "clock recovery ratio does not fit",
            ConfigError::FrequencyOutOfRange => "carrier outside 240-960 MHz",
            ConfigError::InvalidPreamble => "invalid preamble length or threshold",
            ConfigError::InvalidSyncWord => "sync word must be 1-4 bytes",
            ConfigError::InvalidHeader => "header longer than 4 bytes or checks unsent bytes",
            ConfigError::InvalidLength => "fixed packet length of 0",
            ConfigError::TxPowerOutOfRange => "TX power outside 1-20 dBm",
            ConfigError::InvalidFifoThreshold => "FIFO threshold outside 1-63",
        };
        f.write_str(text)
    }
}

impl core::error::Error for ConfigError {}
