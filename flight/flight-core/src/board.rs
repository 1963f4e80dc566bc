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

/// The motor timers as the firmware starts them on both boards (`MotorParts::start`):
/// outputs 1–2 on TIM3 (APB1, timer clock 84 MHz), 3–4 on TIM9 (APB2, 168 MHz), both
/// 16-bit. Settings validation checks the output protocol against each, exactly as the
/// motor task will.
pub const MOTOR_TIMER_CLOCKS: [crate::outputs::TimerClock; 2] = [
    crate::outputs::TimerClock {
        clock_hz: 84_000_000,
        max_count: 0xFFFF,
    },
    crate::outputs::TimerClock {
        clock_hz: 168_000_000,
        max_count: 0xFFFF,
    },
];
