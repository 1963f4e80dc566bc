//! The inputs of a modem calculation: what is asked of the calculator.

use super::Modulation;
use crate::if_filter::IfFilter;

/// The inputs of a modem calculation. Build with [`ModemSettings::new`] and the `with_*`
/// methods (all `const`), then turn into registers with [`ModemConfig::from_settings`](super::ModemConfig::from_settings).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModemSettings {
    /// Air bit rate, 1 000–256 000 bps.
    pub bit_rate_bps: u32,
    /// Transmitted frequency deviation (peak), 625 Hz steps, up to 319 375 Hz.
    pub deviation_hz: u32,
    /// The deviation the receiver is designed for (IF bandwidth and clock-recovery gain).
    /// Normally equal to `deviation_hz`; some published profiles used a larger design value.
    pub rx_deviation_hz: u32,
    /// GFSK or FSK.
    pub modulation: Modulation,
    /// Manchester coding (doubles the chip rate the receiver sees).
    pub manchester: bool,
    /// 0x70 bits 3:2 (manppol, enmaninv). Reset value: set. They only act with Manchester on.
    pub manchester_inverted: bool,
    /// Automatic frequency control (0x1D = 0x40).
    pub afc: bool,
    /// Force an IF filter instead of the calculator's choice.
    pub if_filter: Option<IfFilter>,
    /// Force the AFC limiter (0x2A) instead of the calculator's choice.
    pub afc_limiter: Option<u8>,
}

impl ModemSettings {
    /// GFSK at `bit_rate_bps` with `deviation_hz`, AFC on, calculator choices.
    pub const fn new(bit_rate_bps: u32, deviation_hz: u32) -> Self {
        Self {
            bit_rate_bps,
            deviation_hz,
            rx_deviation_hz: deviation_hz,
            modulation: Modulation::Gfsk,
            manchester: false,
            manchester_inverted: true,
            afc: true,
            if_filter: None,
            afc_limiter: None,
        }
    }

    /// Sets the modulation.
    pub const fn with_modulation(mut self, modulation: Modulation) -> Self {
        self.modulation = modulation;
        self
    }

    /// Sets the deviation the receive side is computed for.
    pub const fn with_rx_deviation_hz(mut self, rx_deviation_hz: u32) -> Self {
        self.rx_deviation_hz = rx_deviation_hz;
        self
    }

    /// Forces an IF filter.
    pub const fn with_if_filter(mut self, filter: IfFilter) -> Self {
        self.if_filter = Some(filter);
        self
    }

    /// Forces the AFC limiter register value.
    pub const fn with_afc_limiter(mut self, limiter: u8) -> Self {
        self.afc_limiter = Some(limiter);
        self
    }

    /// Turns AFC on or off.
    pub const fn with_afc(mut self, afc: bool) -> Self {
        self.afc = afc;
        self
    }

    /// Turns Manchester coding on or off.
    pub const fn with_manchester(mut self, manchester: bool) -> Self {
        self.manchester = manchester;
        self
    }

    /// Sets 0x70 bits 3:2 (see the field).
    pub const fn with_manchester_inverted(mut self, inverted: bool) -> Self {
        self.manchester_inverted = inverted;
        self
    }
}
