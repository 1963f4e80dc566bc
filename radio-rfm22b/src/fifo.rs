//! The two 64-byte FIFOs (datasheet, "FIFO Mode"): their thresholds (0x7C–0x7E) and how packets
//! longer than a FIFO are streamed through them, plus the FIFO clear (0x08).

use crate::ConfigError;

/// Depth of each FIFO.
pub const FIFO_LEN: usize = 64;

/// The FIFO thresholds. A packet longer than 64 bytes is refilled whenever the TX FIFO falls
/// to `tx_almost_empty`, and drained whenever the RX FIFO reaches `rx_almost_full`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FifoThresholds {
    /// 0x7C: TX almost-full (unused by the driver's interrupts; Tau Labs' 62).
    pub tx_almost_full: u8,
    /// 0x7D: TX almost-empty, 1–63 bytes.
    pub tx_almost_empty: u8,
    /// 0x7E: RX almost-full, 1–63 bytes.
    pub rx_almost_full: u8,
}

impl Default for FifoThresholds {
    fn default() -> Self {
        Self::HALF
    }
}

impl FifoThresholds {
    /// Tau Labs' 62 / 32 / 32: half a FIFO of slack each way, i.e. one refill or drain
    /// every 32 bytes (2.2 ms at 115 kbps, far longer than an SPI burst).
    pub const HALF: Self = Self {
        tx_almost_full: 62,
        tx_almost_empty: 32,
        rx_almost_full: 32,
    };

    /// Checks the ranges.
    pub const fn validate(&self) -> Result<(), ConfigError> {
        const fn ok(t: u8) -> bool {
            t >= 1 && t <= 63
        }
        if ok(self.tx_almost_full) && ok(self.tx_almost_empty) && ok(self.rx_almost_full) {
            Ok(())
        } else {
            Err(ConfigError::InvalidFifoThreshold)
        }
    }

    /// Registers 0x7C, 0x7D, 0x7E.
    pub const fn registers(&self) -> [u8; 3] {
        [
            self.tx_almost_full,
            self.tx_almost_empty,
            self.rx_almost_full,
        ]
    }

    /// Bytes that may be written on a TX almost-empty interrupt: the FIFO holds at most
    /// `tx_almost_empty` bytes then; one byte of margin as Tau Labs keeps (64 − 32 − 1).
    pub const fn tx_refill_len(&self) -> usize {
        FIFO_LEN - self.tx_almost_empty as usize - 1
    }

    /// Bytes that may be read on an RX almost-full interrupt: at least the threshold.
    pub const fn rx_drain_len(&self) -> usize {
        self.rx_almost_full as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds() {
        let t = FifoThresholds::default();
        assert_eq!(t.registers(), [62, 32, 32]);
        assert_eq!(t.tx_refill_len(), 31);
        assert_eq!(t.rx_drain_len(), 32);
        assert!(t.validate().is_ok());
        let bad = FifoThresholds {
            rx_almost_full: 64,
            ..t
        };
        assert_eq!(bad.validate(), Err(ConfigError::InvalidFifoThreshold));
    }
}
