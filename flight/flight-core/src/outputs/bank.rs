//! Output banks: outputs that share a timer share its period, so they must share the
//! protocol and rate (hardware/brushedsparky/README.md, "Pins").

use super::protocol::{Protocol, TimerClock};

/// A group of outputs on one timer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Bank {
    /// Timer name for logs.
    pub timer: &'static str,
    /// Its clock and width.
    pub clock: TimerClock,
    /// Zero-based output indices on it.
    pub outputs: &'static [usize],
}

const APB1_16: TimerClock = TimerClock {
    clock_hz: 84_000_000,
    max_count: 0xFFFF,
};
const APB2_16: TimerClock = TimerClock {
    clock_hz: 168_000_000,
    max_count: 0xFFFF,
};

/// The F405 boards' banks, in Tau Labs' order: TIM3 (outputs 1–2), TIM9 (3–4), TIM5 (5–6,
/// 32-bit), TIM8 (7–8, also the PPM input timer), TIM12 (9–10).
pub const BANKS: [Bank; 5] = [
    Bank {
        timer: "TIM3",
        clock: APB1_16,
        outputs: &[0, 1],
    },
    Bank {
        timer: "TIM9",
        clock: APB2_16,
        outputs: &[2, 3],
    },
    Bank {
        timer: "TIM5",
        clock: TimerClock {
            clock_hz: 84_000_000,
            max_count: u32::MAX,
        },
        outputs: &[4, 5],
    },
    Bank {
        timer: "TIM8",
        clock: APB2_16,
        outputs: &[6, 7],
    },
    Bank {
        timer: "TIM12",
        clock: APB1_16,
        outputs: &[8, 9],
    },
];

/// Why an output assignment cannot be built.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BankError {
    /// Two outputs on one timer were given different protocols or rates.
    Conflict {
        /// The timer they share.
        timer: &'static str,
    },
    /// An output index beyond the board's outputs.
    NoSuchOutput(usize),
}

/// Checks that every output used (`Some`) agrees with the others on its timer.
pub fn check_assignment(outputs: &[Option<Protocol>]) -> Result<(), BankError> {
    if let Some(extra) = (10..outputs.len()).find(|&i| matches!(outputs.get(i), Some(Some(_)))) {
        return Err(BankError::NoSuchOutput(extra));
    }
    for bank in &BANKS {
        let mut used = bank
            .outputs
            .iter()
            .filter_map(|&i| outputs.get(i).copied().flatten());
        if let Some(first) = used.next()
            && used.any(|p| p != first)
        {
            return Err(BankError::Conflict { timer: bank.timer });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brushed_quad_on_outputs_1_to_4_is_fine() {
        let b = Some(Protocol::Brushed {
            frequency_hz: 32_000,
        });
        assert_eq!(check_assignment(&[b, b, b, b]), Ok(()));
    }

    #[test]
    fn mixed_protocols_on_one_timer_are_refused() {
        let b = Some(Protocol::Brushed {
            frequency_hz: 32_000,
        });
        let o = Some(Protocol::OneShot125);
        assert_eq!(
            check_assignment(&[b, b, b, o]),
            Err(BankError::Conflict { timer: "TIM9" })
        );
        assert_eq!(check_assignment(&[b, b, o, o]), Ok(()));
        let mut eleven = [None; 11];
        eleven[10] = o;
        assert_eq!(check_assignment(&eleven), Err(BankError::NoSuchOutput(10)));
    }
}
