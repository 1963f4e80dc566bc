//! The slot schedule: one packet per slot, hopping every slot; slot `s` is a downlink
//! (follower → master) slot when `s mod N = N − 1`, N being the telemetry ratio, and an
//! uplink (channels, master → follower) slot otherwise. See `spec/protocol.md` §4 for why
//! a downlink replaces an uplink instead of sharing its slot.

use super::rate::{PLL_SETTLE_US, RateMode};

/// Direction of one slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SlotKind {
    /// Master transmits channels (and stream data).
    Uplink,
    /// Follower transmits telemetry.
    Downlink,
}

/// Timing of a bound link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Schedule {
    /// Rate mode.
    pub rate: RateMode,
    /// One slot in this many is a downlink slot (power of two, ≥ 2).
    pub telemetry_ratio: u8,
}

impl Schedule {
    /// Slot length.
    pub const fn slot_us(&self) -> u32 {
        self.rate.slot_us()
    }

    /// Direction of slot `slot`.
    pub const fn kind(&self, slot: u32) -> SlotKind {
        let n = self.telemetry_ratio as u32;
        if n >= 2 && slot % n == n - 1 {
            SlotKind::Downlink
        } else {
            SlotKind::Uplink
        }
    }

    /// Channel updates per second: the uplink slots.
    pub const fn channel_rate_millihz(&self) -> u32 {
        let n = self.telemetry_ratio as u32;
        self.rate.slot_rate_hz() * 1000 * (n - 1) / n
    }

    /// When, after its slot starts, a packet of `frame_bytes` has fully arrived.
    pub const fn packet_end_offset_us(&self, frame_bytes: usize) -> u32 {
        self.rate.tx_lead_us()
            + self.rate.tx_setup_us()
            + PLL_SETTLE_US
            + self.rate.airtime_us(frame_bytes)
    }

    /// When, after its slot starts, a receiver stops waiting for this slot's packet.
    pub const fn listen_end_offset_us(&self) -> u32 {
        self.slot_us() - self.rate.tail_guard_us() / 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downlink_every_nth() {
        let s = Schedule {
            rate: RateMode::F500,
            telemetry_ratio: 4,
        };
        let kinds: Vec<_> = (0..8).map(|k| s.kind(k)).collect();
        assert_eq!(
            kinds.iter().filter(|k| **k == SlotKind::Downlink).count(),
            2
        );
        assert_eq!(s.kind(3), SlotKind::Downlink);
        assert_eq!(s.kind(7), SlotKind::Downlink);
        assert_eq!(s.channel_rate_millihz(), 375_000);
        // 256 (the wire counter's period) is a multiple of every ratio: phase survives wrap.
        assert_eq!(s.kind(255), SlotKind::Downlink);
    }

    #[test]
    fn largest_packet_ends_before_listening_stops() {
        for rate in RateMode::ALL {
            let s = Schedule {
                rate,
                telemetry_ratio: 2,
            };
            assert!(s.packet_end_offset_us(rate.max_frame_bytes()) < s.listen_end_offset_us());
        }
    }
}
