//! TEMP's calibration registers A0–A5, B0–B5, T0–T4 (PS "TEMP"), which embassy-nrf's `init`
//! fills from FICR (nRF52832/52840 anomaly 66). The image never measures a temperature, so
//! the measurement tasks are not modelled (an access to them is recorded as unmodelled).

/// The TEMP calibration registers.
pub struct Temp {
    regs: [u32; 17],
}

/// Offsets of A0, B0 and T0.
const A0: u32 = 0x520;
const B0: u32 = 0x540;
const T0: u32 = 0x560;

fn slot(offset: u32) -> Option<usize> {
    let i = match offset {
        A0..0x538 => (offset - A0) / 4,
        B0..0x558 => 6 + (offset - B0) / 4,
        T0..0x574 => 12 + (offset - T0) / 4,
        _ => return None,
    };
    Some(i as usize)
}

impl Temp {
    /// Reset state.
    pub const fn new() -> Self {
        Self { regs: [0; 17] }
    }

    /// A register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        self.regs.get(slot(offset)?).copied()
    }

    /// A register write; false if not implemented.
    pub fn write(&mut self, offset: u32, value: u32) -> bool {
        match slot(offset).and_then(|i| self.regs.get_mut(i)) {
            Some(r) => {
                *r = value;
                true
            }
            None => false,
        }
    }
}
