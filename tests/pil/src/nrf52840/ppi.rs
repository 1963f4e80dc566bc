//! PPI (PS "PPI"): twenty programmable channels, each an event end point (EEP) and a task
//! end point (TEP) plus a FORK task, enabled by CHEN/CHENSET/CHENCLR or the channel-group
//! tasks; the twelve pre-programmed channels (20–31, radio and RTC0 wiring) are not
//! modelled and noted if enabled. An event reaches every enabled channel whose EEP is its
//! register address, in the same instant.

/// Programmable channels.
const CHANNELS: usize = 20;
/// Channel groups.
const GROUPS: usize = 6;

/// The PPI.
pub struct Ppi {
    chen: u32,
    eep: [u32; CHANNELS],
    tep: [u32; CHANNELS],
    fork: [u32; 32],
    chg: [u32; GROUPS],
}

impl Default for Ppi {
    fn default() -> Self {
        Self::new()
    }
}

impl Ppi {
    /// Reset state.
    pub const fn new() -> Self {
        Self {
            chen: 0,
            eep: [0; CHANNELS],
            tep: [0; CHANNELS],
            fork: [0; 32],
            chg: [0; GROUPS],
        }
    }

    /// The task addresses event `event` triggers, in channel order (TEP, then FORK).
    pub fn tasks_for(&self, event: u32) -> Vec<u32> {
        let mut tasks = Vec::new();
        for n in 0..CHANNELS {
            if self.chen & (1 << n) == 0 || self.eep.get(n) != Some(&event) {
                continue;
            }
            for t in [self.tep.get(n), self.fork.get(n)].into_iter().flatten() {
                if *t != 0 {
                    tasks.push(*t);
                }
            }
        }
        tasks
    }

    /// Whether a pre-programmed channel (20–31) is enabled.
    pub const fn fixed_channels_enabled(&self) -> bool {
        self.chen & 0xFFF0_0000 != 0
    }

    /// A register read.
    pub fn read(&self, offset: u32) -> Option<u32> {
        Some(match offset {
            0x500..=0x508 => self.chen,
            0x510..0x5B0 => {
                let n = ((offset - 0x510) / 8) as usize;
                if offset.is_multiple_of(8) {
                    *self.eep.get(n)?
                } else {
                    *self.tep.get(n)?
                }
            }
            0x800..0x818 => *self.chg.get(((offset - 0x800) / 4) as usize)?,
            0x910..0x990 => *self.fork.get(((offset - 0x910) / 4) as usize)?,
            _ => return None,
        })
    }

    /// A register write (the group tasks included); false if not implemented.
    pub fn write(&mut self, offset: u32, value: u32) -> bool {
        match offset {
            0x000..0x030 => {
                let Some(&group) = self.chg.get((offset / 8) as usize) else {
                    return false;
                };
                if value & 1 != 0 {
                    if offset.is_multiple_of(8) {
                        self.chen |= group;
                    } else {
                        self.chen &= !group;
                    }
                }
            }
            0x500 => self.chen = value,
            0x504 => self.chen |= value,
            0x508 => self.chen &= !value,
            0x510..0x5B0 => {
                let n = ((offset - 0x510) / 8) as usize;
                let slot = if offset.is_multiple_of(8) {
                    self.eep.get_mut(n)
                } else {
                    self.tep.get_mut(n)
                };
                let Some(slot) = slot else { return false };
                *slot = value;
            }
            0x800..0x818 => {
                let Some(g) = self.chg.get_mut(((offset - 0x800) / 4) as usize) else {
                    return false;
                };
                *g = value;
            }
            0x910..0x990 => {
                let Some(f) = self.fork.get_mut(((offset - 0x910) / 4) as usize) else {
                    return false;
                };
                *f = value;
            }
            _ => return false,
        }
        true
    }

    /// Reset state.
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}
