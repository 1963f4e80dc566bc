//! Link quality: LQ as the share of the last 100 expected packets that arrived (ExpressLRS'
//! `LQCALC<100>`), smoothed RSSI, and packet counters.

/// Window length of the LQ figure.
pub const LQ_WINDOW: usize = 100;

/// A 100-entry bit ring of "expected packet arrived?".
#[derive(Clone, Debug, Default)]
pub struct LqWindow {
    bits: [u32; 4],
    head: usize,
    filled: usize,
    hits: usize,
}

impl LqWindow {
    /// An empty window.
    pub const fn new() -> Self {
        Self {
            bits: [0; 4],
            head: 0,
            filled: 0,
            hits: 0,
        }
    }

    fn bit(&self, i: usize) -> bool {
        self.bits
            .get(i / 32)
            .is_some_and(|w| w & (1 << (i % 32)) != 0)
    }

    /// Records one expected packet.
    pub fn push(&mut self, arrived: bool) {
        if self.filled == LQ_WINDOW {
            if self.bit(self.head) {
                self.hits -= 1;
            }
        } else {
            self.filled += 1;
        }
        if let Some(word) = self.bits.get_mut(self.head / 32) {
            let mask = 1u32 << (self.head % 32);
            if arrived {
                *word |= mask;
            } else {
                *word &= !mask;
            }
        }
        if arrived {
            self.hits += 1;
        }
        self.head = (self.head + 1) % LQ_WINDOW;
    }

    /// LQ in percent of the expected packets so far (up to the last 100); 0 when nothing
    /// was expected yet.
    pub fn percent(&self) -> u8 {
        (self.hits * 100)
            .checked_div(self.filled)
            .map_or(0, |p| p as u8)
    }

    /// Forgets everything (after a resync: LQ counts up again, as in ExpressLRS).
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}

/// RSSI smoothed with a 1/8 exponential filter in 1/16 dB fixed point (integer-only, so it
/// costs nothing on the M4 and is exactly reproducible).
#[derive(Clone, Copy, Debug, Default)]
pub struct RssiFilter {
    sixteenths: Option<i32>,
}

impl RssiFilter {
    /// Feeds one packet's RSSI.
    pub fn push(&mut self, rssi_dbm: i16) {
        let x = i32::from(rssi_dbm) * 16;
        self.sixteenths = Some(match self.sixteenths {
            None => x,
            // Rounded step, so the filter settles within 1/4 dB of a constant input.
            Some(s) => {
                let d = x - s;
                s + (d + d.signum() * 4) / 8
            }
        });
    }

    /// Smoothed RSSI in whole dBm, if any packet was seen.
    pub fn dbm(&self) -> Option<i16> {
        self.sixteenths.map(|s| (s + 8).div_euclid(16) as i16)
    }

    /// As an `i8` for the air report (saturating; the Si4432 reads −122..0 dBm anyway).
    pub fn report_dbm(&self) -> i8 {
        self.dbm().map_or(i8::MIN, |d| d.clamp(-128, 127) as i8)
    }
}

/// Packet counters of one end.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Packets sent.
    pub sent: u32,
    /// Valid packets of this link received.
    pub received: u32,
    /// Expected packets that did not arrive (timeout).
    pub missed: u32,
    /// Packets that arrived but were rejected (CRC, version, kind, foreign link).
    pub rejected: u32,
    /// Radio errors (bus, chip reset, FIFO, TX timeout) the link loop met; each was followed
    /// by a re-configure of the radio.
    pub radio_errors: u32,
    /// Keyed links: frames of this link whose authentication tag failed (also counted in
    /// `rejected`): forgeries, replays, or — rarely — corruption that passed the chip's
    /// CRC-16 (spec §12.2, "Tag failures").
    pub tag_failures: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lq_counts_the_last_hundred() {
        let mut lq = LqWindow::new();
        assert_eq!(lq.percent(), 0);
        for i in 0..100 {
            lq.push(i % 10 != 0);
        }
        assert_eq!(lq.percent(), 90);
        for _ in 0..50 {
            lq.push(false);
        }
        // last 100: 50 from the old pattern (45 hits) + 50 misses
        assert_eq!(lq.percent(), 45);
        for _ in 0..100 {
            lq.push(true);
        }
        assert_eq!(lq.percent(), 100);
    }

    #[test]
    fn lq_partial_window() {
        let mut lq = LqWindow::new();
        lq.push(true);
        lq.push(false);
        lq.push(true);
        lq.push(true);
        assert_eq!(lq.percent(), 75);
        lq.reset();
        assert_eq!(lq.percent(), 0);
    }

    #[test]
    fn rssi_filter_converges() {
        let mut f = RssiFilter::default();
        assert_eq!(f.dbm(), None);
        assert_eq!(f.report_dbm(), i8::MIN);
        f.push(-90);
        assert_eq!(f.dbm(), Some(-90));
        for _ in 0..100 {
            f.push(-60);
        }
        assert_eq!(f.dbm(), Some(-60));
        f.push(-124);
        assert_eq!(f.dbm(), Some(-68));
    }
}
