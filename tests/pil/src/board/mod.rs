//! The boards around the microcontrollers: each an [`Outside`](crate::wire::Outside)
//! implementation that names its pins once (from `hardware/*/README.md` and the firmware's
//! `board.rs`, the same facts) and routes what the MCU model does on them to the chip
//! models of [`crate::chips`].
//!
//! - [`flight`]: the BrushedSparky and the Sparky2 (STM32F405), one board with the two
//!   revisions' differences as data;
//! - [`module`]: the TauLink module (nRF52840, nice!nano-class).
//!
//! What the chips do on their own (a sample's data-ready, nIRQ, a PPM edge, a byte on a
//! UART) reaches the MCU as timestamped inputs the co-simulation hands to the SoC model
//! before it runs past them ([`Outbox`]); a change the MCU causes itself (an interrupt
//! cleared by a read) is stamped with the instant of that access and handed over at the
//! end of the step, up to one quantum late (`crate::world`).

pub mod flight;
pub mod module;

use crate::wire::Pin;

/// An input for the MCU, with its time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input {
    /// A pin's level from `at_ns` on.
    Pin {
        /// The pin.
        pin: Pin,
        /// Its level.
        level: bool,
        /// From, ns.
        at_ns: u64,
    },
    /// A byte whose stop bit ends at `at_ns` on UART `uart` (the SoC model's numbering).
    Uart {
        /// The UART.
        uart: u8,
        /// The byte.
        byte: u8,
        /// End of its stop bit, ns.
        at_ns: u64,
    },
}

impl Input {
    /// When it happens, ns.
    pub fn at_ns(&self) -> u64 {
        match *self {
            Input::Pin { at_ns, .. } | Input::Uart { at_ns, .. } => at_ns,
        }
    }
}

/// The inputs a board has produced and the co-simulation has not handed to the SoC yet.
#[derive(Debug, Clone, Default)]
pub struct Outbox {
    inputs: Vec<Input>,
}

impl Outbox {
    /// Queues a pin level.
    pub fn pin(&mut self, pin: Pin, level: bool, at_ns: u64) {
        self.inputs.push(Input::Pin { pin, level, at_ns });
    }

    /// Queues a UART byte.
    pub fn uart(&mut self, uart: u8, byte: u8, at_ns: u64) {
        self.inputs.push(Input::Uart { uart, byte, at_ns });
    }

    /// Everything queued, in time order (stable for equal times).
    pub fn take(&mut self) -> Vec<Input> {
        let mut v = std::mem::take(&mut self.inputs);
        v.sort_by_key(Input::at_ns);
        v
    }
}

/// A recorded digital output (LED, buzzer): its changes with their times.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Trace {
    /// (time ns, level high), only changes.
    pub edges: Vec<(u64, bool)>,
}

impl Trace {
    /// The output is now `high` (recorded when it changed).
    pub fn set(&mut self, at_ns: u64, high: bool) {
        if self.edges.last().map(|e| e.1) != Some(high) {
            self.edges.push((at_ns, high));
        }
    }

    /// The level at `t_ns` (low before the first change).
    pub fn level_at(&self, t_ns: u64) -> bool {
        self.edges
            .iter()
            .take_while(|e| e.0 <= t_ns)
            .last()
            .is_some_and(|e| e.1)
    }
}

/// What the MCU's SPI controller reads on MISO when no chip drives it: the idle line
/// (the boards leave MISO without a pull; the STM32's and nRF's inputs read a floating line
/// as whatever it last was, taken as all ones).
pub const MISO_FLOATING: u8 = 0xFF;

/// Port letters for messages (0 = A / P0 …).
pub fn pin_name(pin: Pin, stm32: bool) -> String {
    if stm32 {
        let port = char::from(b'A' + pin.port);
        format!("P{port}{}", pin.pin)
    } else {
        format!("P{}.{:02}", pin.port, pin.pin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_outbox_hands_inputs_over_in_time_order() {
        let mut o = Outbox::default();
        o.pin(Pin::new(2, 5), true, 30);
        o.uart(1, 0xB5, 10);
        o.pin(Pin::new(2, 5), false, 30);
        let got = o.take();
        assert_eq!(
            got.iter().map(Input::at_ns).collect::<Vec<_>>(),
            vec![10, 30, 30]
        );
        assert!(matches!(got[1], Input::Pin { level: true, .. }));
        assert!(o.take().is_empty());
        let mut t = Trace::default();
        t.set(5, true);
        t.set(6, true);
        t.set(9, false);
        assert_eq!(t.edges.len(), 2);
        assert!(t.level_at(7) && !t.level_at(9) && !t.level_at(1));
        assert_eq!(pin_name(Pin::new(2, 4), true), "PC4");
        assert_eq!(pin_name(Pin::new(1, 0), false), "P1.00");
    }
}
