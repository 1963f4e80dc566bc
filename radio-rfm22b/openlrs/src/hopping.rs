//! The hop sequence: index n mod hopcount through the 0-terminated list, and what each hop
//! programs. Timing of hops lives in the role state machines.

use super::bind::{BindData, MAX_HOPS};
use super::modem;

/// One hop slot as the radio sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hop {
    /// Index into the hop list (what the header XOR uses).
    pub index: u8,
    /// Channel number written to 0x79.
    pub channel: u8,
    /// The 4 header bytes on air (0x3A..0x3D), last one XORed with `index`.
    pub header: [u8; 4],
    /// Resulting carrier.
    pub frequency_hz: u32,
}

/// The next hop index after `index`: wraps at 24 or at the first 0 entry (TX.h / RX.h).
pub fn next_index(data: &BindData, index: u8) -> u8 {
    let next = index.wrapping_add(1);
    if usize::from(next) >= MAX_HOPS || data.hop_channels.get(usize::from(next)) == Some(&0) {
        0
    } else {
        next
    }
}

/// Describes hop slot `index`; `None` past the list.
pub fn hop(data: &BindData, index: u8) -> Option<Hop> {
    Some(Hop {
        index,
        channel: *data.hop_channels.get(usize::from(index))?,
        header: modem::link_header(data.rf_magic, index),
        frequency_hz: modem::hop_frequency_hz(data, index)?,
    })
}

/// Iterates the hop slots the TX uses for packets 0, 1, 2, ….
#[derive(Debug, Clone)]
pub struct Schedule<'a> {
    data: &'a BindData,
    index: u8,
}

impl<'a> Schedule<'a> {
    /// Starts at index 0, as the TX does after `init_rfm`.
    pub fn new(data: &'a BindData) -> Self {
        Self { data, index: 0 }
    }
}

impl Iterator for Schedule<'_> {
    type Item = Hop;

    fn next(&mut self) -> Option<Hop> {
        let h = hop(self.data, self.index)?;
        self.index = next_index(self.data, self.index);
        Some(h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BindingVersion, RfmType};

    #[test]
    fn default_schedule_wraps_after_six() {
        let d = BindData::defaults(BindingVersion::V38, RfmType::Mhz433);
        let ch: [u8; 8] = {
            let mut s = Schedule::new(&d);
            core::array::from_fn(|_| s.next().unwrap().channel)
        };
        assert_eq!(ch, [22, 10, 19, 34, 49, 41, 22, 10]);
    }
}
