//! Board facts that the logic needs (not pins: those live in the firmware's `board.rs`).

/// Which flight-controller board the firmware runs on (hardware/brushedsparky/README.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Board {
    /// BrushedSparky: 1S, on-board brushed-motor FETs, RFM22B nIRQ on PB7.
    BrushedSparky,
    /// Sparky2: servo/ESC headers, RFM22B nIRQ on PD2.
    Sparky2,
}

impl Board {
    /// Battery-sense divider ratio (VBAT / V_adc) on PC3: 10 k/10 k on the BrushedSparky; the
    /// Sparky2 has none on board and takes an external sensor (AttoPilot-style 63.69 mV/V).
    pub const fn battery_divider(self) -> f32 {
        match self {
            Board::BrushedSparky => 2.0,
            Board::Sparky2 => 1000.0 / 63.69,
        }
    }
}
