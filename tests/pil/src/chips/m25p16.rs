//! The Micron/ST M25P16 16-Mbit serial flash on SPI (M25P16 datasheet, "Instructions"):
//! the first byte after S# falls is the instruction; RDID (0x9F: manufacturer 0x20, memory
//! type 0x20, capacity 0x15), RDSR (0x05: WIP, WEL), WREN (0x06) / WRDI (0x04), READ (0x03
//! with a 3-byte address: an erased chip reads 0xFF), DP (0xB9, deep power-down: only RES
//! answers) and RES (0xAB: leaves deep power-down, the old electronic signature 0x14).
//! While S# is high, Q is high impedance: the chip is silent. Programming and erasing are
//! not modelled yet (a later issue logs to it): PP and SE are accepted and change nothing.

/// RDID: manufacturer, memory type, memory capacity (2^0x15 = 2 MiB).
pub const JEDEC_ID: [u8; 3] = [0x20, 0x20, 0x15];
/// RES: the electronic signature.
pub const SIGNATURE: u8 = 0x14;

/// The transaction in progress: the instruction and how many bytes followed it.
#[derive(Debug, Clone, Copy)]
struct Transaction {
    instruction: Option<u8>,
    count: usize,
}

/// The chip.
#[derive(Debug, Clone, Default)]
pub struct M25p16 {
    selected: Option<Transaction>,
    wel: bool,
    deep_power_down: bool,
}

impl M25p16 {
    /// A chip after power-on.
    pub fn new() -> Self {
        Self::default()
    }

    /// S# as the MCU drives it (low = selected). An instruction ends when S# rises.
    pub fn select(&mut self, low: bool) {
        if low && self.selected.is_none() {
            self.selected = Some(Transaction {
                instruction: None,
                count: 0,
            });
        } else if !low {
            if let Some(Transaction {
                instruction: Some(i),
                ..
            }) = self.selected
            {
                self.end(i);
            }
            self.selected = None;
        }
    }

    fn end(&mut self, instruction: u8) {
        match instruction {
            0x06 if !self.deep_power_down => self.wel = true,
            0x04 if !self.deep_power_down => self.wel = false,
            0xB9 => self.deep_power_down = true,
            0xAB => self.deep_power_down = false,
            _ => {}
        }
    }

    /// One byte on C/D: what Q drives (`None`: high impedance — deselected, or no data).
    pub fn byte(&mut self, mosi: u8) -> Option<u8> {
        let mut tx = self.selected?;
        let Some(instruction) = tx.instruction else {
            tx.instruction = Some(mosi);
            self.selected = Some(tx);
            return None;
        };
        let k = tx.count;
        tx.count += 1;
        self.selected = Some(tx);
        if self.deep_power_down {
            // RES: three dummy bytes, then the signature.
            return (instruction == 0xAB && k >= 3).then_some(SIGNATURE);
        }
        match instruction {
            0x9F => JEDEC_ID.get(k).copied(),
            0x05 => Some(u8::from(self.wel) << 1),
            0x03 | 0x0B if k >= 3 => Some(0xFF),
            0xAB if k >= 3 => Some(SIGNATURE),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tx(chip: &mut M25p16, bytes: &[u8]) -> Vec<Option<u8>> {
        chip.select(true);
        let out = bytes.iter().map(|&b| chip.byte(b)).collect();
        chip.select(false);
        out
    }

    #[test]
    fn jedec_id_status_and_silence_when_deselected() {
        let mut f = M25p16::new();
        assert_eq!(
            tx(&mut f, &[0x9F, 0, 0, 0]),
            vec![None, Some(0x20), Some(0x20), Some(0x15)]
        );
        assert_eq!(f.byte(0x9F), None, "S# high: Q high impedance");
        assert_eq!(tx(&mut f, &[0x05, 0]), vec![None, Some(0x00)]);
        tx(&mut f, &[0x06]);
        assert_eq!(tx(&mut f, &[0x05, 0]), vec![None, Some(0x02)], "WEL");
        tx(&mut f, &[0x04]);
        assert_eq!(tx(&mut f, &[0x05, 0])[1], Some(0x00));
        // Erased: 0xFF after the address.
        assert_eq!(tx(&mut f, &[0x03, 0, 0x10, 0, 0])[4], Some(0xFF));
    }

    #[test]
    fn deep_power_down_answers_only_res() {
        let mut f = M25p16::new();
        tx(&mut f, &[0xB9]);
        assert_eq!(tx(&mut f, &[0x9F, 0, 0, 0]), vec![None; 4]);
        assert_eq!(tx(&mut f, &[0xAB, 0, 0, 0, 0])[4], Some(SIGNATURE));
        assert_eq!(tx(&mut f, &[0x9F, 0])[1], Some(0x20), "awake again");
    }
}
