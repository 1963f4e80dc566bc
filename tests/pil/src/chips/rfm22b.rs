//! An RFM22B module: a `si4432-sim` chip (register level, on the shared RF medium) behind
//! the module's pins. nSEL's falling edge starts a transaction and each byte the MCU's SPI
//! controller clocks acts on the chip at once (one transaction per nSEL low period, as the
//! Si4432 datasheet's SPI timing has it); nIRQ's changes come out with the chip's own times
//! for the board to queue on the MCU's input; SDN (high = shutdown, low = a power-on reset)
//! where the board wires it.

use si4432_sim::{ChipHandle, RadioHandle, RadioId};

use super::Edge;

/// One RFM22B.
pub struct Rfm22b {
    radio: RadioHandle,
    selected: bool,
    shut_down: bool,
}

impl core::fmt::Debug for Rfm22b {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Rfm22b")
            .field("id", &self.radio.id)
            .field("selected", &self.selected)
            .field("shut_down", &self.shut_down)
            .finish()
    }
}

impl Rfm22b {
    /// The module around `radio` (from `Medium::add_radio`), nSEL high.
    pub fn new(radio: RadioHandle) -> Self {
        radio.chip.record_nirq_edges();
        Self {
            radio,
            selected: false,
            shut_down: false,
        }
    }

    /// The chip's handle (faults, inspection).
    pub fn chip(&self) -> &ChipHandle {
        &self.radio.chip
    }

    /// Its id on the medium.
    pub fn id(&self) -> RadioId {
        self.radio.id
    }

    /// nSEL as the MCU drives it (low = selected).
    pub fn nsel(&mut self, low: bool) {
        if low && !self.selected {
            self.radio.chip.select();
        } else if !low && self.selected {
            self.radio.chip.deselect();
        }
        self.selected = low;
    }

    /// One byte on SCK/SDI: what SDO drives back (`None`: tri-stated).
    pub fn byte(&mut self, mosi: u8) -> Option<u8> {
        if self.shut_down {
            return None;
        }
        self.radio.chip.clock_byte(mosi)
    }

    /// SDN as the board holds it (high = shutdown; low again = a power-on reset).
    pub fn sdn(&mut self, high: bool) {
        use embedded_hal::digital::OutputPin;
        if high == self.shut_down {
            return;
        }
        self.shut_down = high;
        let _ = if high {
            self.radio.sdn.set_high()
        } else {
            self.radio.sdn.set_low()
        };
    }

    /// The board's supply comes up: a power-on reset of the chip (registers lost, `ipor`
    /// after the POR time).
    pub fn power_on(&mut self) {
        self.selected = false;
        self.radio.chip.deselect();
        self.radio.chip.power_on_reset();
    }

    /// nIRQ's level now (true = high, released).
    pub fn nirq_high(&self) -> bool {
        !self.radio.chip.nirq_is_low()
    }

    /// nIRQ's changes since the last call, (time ns, level high) in time order.
    pub fn take_nirq_edges(&mut self) -> Vec<Edge> {
        self.radio
            .chip
            .take_nirq_edges()
            .into_iter()
            .map(|(t, low)| (t, !low))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use si4432_sim::{RadioConfig, Simulation};

    #[test]
    fn a_transaction_per_nsel_low_and_sdn_resets() {
        let sim = Simulation::new(3);
        let medium = sim.medium();
        let mut rfm = Rfm22b::new(medium.add_radio(RadioConfig::default()));
        assert_eq!(rfm.byte(0x00), None, "deselected: SDO tri-stated");
        rfm.nsel(true);
        assert_eq!(rfm.byte(0x00), Some(0x00));
        assert_eq!(rfm.byte(0x00), Some(0x08), "device type");
        rfm.nsel(false);
        // Clear the power-up interrupts: nIRQ rises, stamped at time 0.
        assert!(!rfm.nirq_high());
        rfm.nsel(true);
        rfm.byte(0x03);
        rfm.byte(0);
        rfm.byte(0);
        rfm.nsel(false);
        assert!(rfm.nirq_high());
        assert_eq!(rfm.take_nirq_edges(), vec![(0, true)]);
        // Shutdown: nothing answers; back on: a power-on reset, ipor after 15 ms.
        rfm.sdn(true);
        rfm.nsel(true);
        assert_eq!(rfm.byte(0x00), None);
        rfm.nsel(false);
        rfm.sdn(false);
        medium.advance_to_ns(20_000_000);
        let edges = rfm.take_nirq_edges();
        assert_eq!(edges.last().map(|e| e.1), Some(false), "{edges:?}");
    }
}
