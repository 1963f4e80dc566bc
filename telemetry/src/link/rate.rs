//! Rate modes and their airtime budget: how long a packet occupies the air at each bit rate,
//! and the proof (as `const` arithmetic, checked by tests) that every mode's slot holds the
//! largest packet it allows plus the radio's settling and turnaround times.

/// Si4432 transmit preamble, bytes. 40 bits is the length AN440 recommends with AFC enabled
/// (register 0x34 = 0x0A nibbles; detection threshold 20 bits in 0x35).
pub const PREAMBLE_BYTES: usize = 5;
/// Sync word bytes (`2D D4`, register 0x33 synclen = 1). Fixed: the link identity lives in the
/// header bytes, which the chip checks right after sync.
pub const SYNC_BYTES: usize = 2;
/// Hardware header bytes (0x3A–0x3D on TX, checked against 0x3F–0x42 on RX): derived from the
/// bind ID so the chip drops foreign packets before they reach the FIFO.
pub const HEADER_BYTES: usize = 4;
/// The packet-length byte the Si4432 sends after the header (variable length, 0x33 bit 3 = 0).
pub const LENGTH_BYTES: usize = 1;
/// The chip's own CRC-16 (0x30 = 0x8C: CRC on, CCITT polynomial).
pub const CHIP_CRC_BYTES: usize = 2;
/// Everything the chip adds around our frame.
pub const CHIP_OVERHEAD_BYTES: usize =
    PREAMBLE_BYTES + SYNC_BYTES + HEADER_BYTES + LENGTH_BYTES + CHIP_CRC_BYTES;
/// The Si4432 FIFO is 64 bytes; our frames are loaded in one go, never refilled mid-packet.
pub const FIFO_BYTES: usize = 64;

/// PLL settling after a channel change or a TX/RX enable. OpenLRSng waits 200 µs after each
/// step; the datasheet's TUNE→TX/RX figure is of the same order.
pub const PLL_SETTLE_US: u32 = 200;
/// Time the sender waits after its slot starts before it enables TX, so a receiver whose slot
/// estimate runs a little late is already listening; also covers SPI register writes.
pub const TX_LEAD_US: u32 = 100;
/// SPI work of the sender between its lead and the PLL starting to settle: loading the frame
/// into the FIFO and the driver's register writes (abort, FIFO clear, length, interrupt
/// enable, status clear, TX on). Measured on si4432-sim with SPI time on the F405's 5.25 MHz
/// bus (radio-rfm22b test `transmit_set_up_on_the_spi_bus_fits_the_link_budget`): ~95 µs for
/// F500's largest frame (32 B), 141 µs for a full 64-byte FIFO; the larger frames of the
/// slower modes overrun it by at most ~40 µs, which their tail guard absorbs. Without this
/// term the largest frames ended after the receiver stopped listening, and at 1:2 telemetry
/// the follower's downlink pushed the master's next uplink later every slot until lock was
/// lost (taulink-sim, chip level, F250).
pub const TX_SETUP_US: u32 = 100;
/// Time kept free at the end of every slot: the receiver drains the FIFO (nIRQ latency, status,
/// header and FIFO reads: ~120 µs for a 32-byte frame at 5.25 MHz) and the next slot's sender
/// turns around (RX→TX) and retunes; that sender's own [`TX_LEAD_US`] follows. 150 µs (200
/// before [`TX_SETUP_US`] was charged separately) keeps 16 channels plus a link report in
/// F500's uplink.
pub const TAIL_GUARD_US: u32 = 150;

/// The airtime of `frame_bytes` of our frame at `bit_rate_bps`, including everything the chip
/// adds (preamble, sync, header, length, chip CRC), in µs, rounded up.
pub const fn airtime_us(frame_bytes: usize, bit_rate_bps: u32) -> u32 {
    let bits = ((frame_bytes + CHIP_OVERHEAD_BYTES) * 8) as u64;
    let rate = bit_rate_bps as u64;
    (bits * 1_000_000).div_ceil(rate) as u32
}

/// A packet-rate mode: bit rate and slot length. One packet per slot, in one direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RateMode {
    /// Long range: 50 slots/s at 19.2 kbps (Tau Labs' and OpenLRSng's default bit rate).
    L50,
    /// 100 slots/s at 57.6 kbps.
    M100,
    /// 250 slots/s at 128 kbps.
    F250,
    /// 500 slots/s at 256 kbps, the Si4432's fastest rate.
    F500,
}

impl RateMode {
    /// All modes, slowest first.
    pub const ALL: [RateMode; 4] = [
        RateMode::L50,
        RateMode::M100,
        RateMode::F250,
        RateMode::F500,
    ];

    /// Air bit rate.
    pub const fn bit_rate_bps(self) -> u32 {
        match self {
            RateMode::L50 => 19_200,
            RateMode::M100 => 57_600,
            RateMode::F250 => 128_000,
            RateMode::F500 => 256_000,
        }
    }

    /// Slot length: the packet period.
    pub const fn slot_us(self) -> u32 {
        match self {
            RateMode::L50 => 20_000,
            RateMode::M100 => 10_000,
            RateMode::F250 => 4_000,
            RateMode::F500 => 2_000,
        }
    }

    /// Slots per second.
    pub const fn slot_rate_hz(self) -> u32 {
        1_000_000 / self.slot_us()
    }

    /// Airtime left for one packet once lead, SPI set-up, PLL settle and tail guard are paid.
    pub const fn packet_budget_us(self) -> u32 {
        self.slot_us() - TX_LEAD_US - TX_SETUP_US - PLL_SETTLE_US - TAIL_GUARD_US
    }

    /// The largest frame (our bytes, excluding the chip's) that fits the slot and the FIFO.
    pub const fn max_frame_bytes(self) -> usize {
        let budget_bits = self.packet_budget_us() as u64 * self.bit_rate_bps() as u64 / 1_000_000;
        let on_air = (budget_bits / 8) as usize;
        let frame = on_air.saturating_sub(CHIP_OVERHEAD_BYTES);
        if frame > FIFO_BYTES {
            FIFO_BYTES
        } else {
            frame
        }
    }

    /// Wire code (bind packets).
    pub const fn code(self) -> u8 {
        match self {
            RateMode::L50 => 0,
            RateMode::M100 => 1,
            RateMode::F250 => 2,
            RateMode::F500 => 3,
        }
    }

    /// Inverse of [`RateMode::code`].
    pub const fn from_code(code: u8) -> Option<RateMode> {
        match code {
            0 => Some(RateMode::L50),
            1 => Some(RateMode::M100),
            2 => Some(RateMode::F250),
            3 => Some(RateMode::F500),
            _ => None,
        }
    }
}

/// The rate mode bind packets travel at: the most robust one.
pub const BIND_RATE: RateMode = RateMode::L50;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn airtime_matches_hand_computation() {
        // 29-byte frame (16 channels) + 14 chip bytes = 43 bytes = 344 bits.
        assert_eq!(airtime_us(29, 256_000), 1344);
        assert_eq!(airtime_us(29, 128_000), 2688);
        assert_eq!(airtime_us(29, 19_200), 17_917);
    }

    #[test]
    fn every_mode_fits_its_largest_frame() {
        for mode in RateMode::ALL {
            let frame = mode.max_frame_bytes();
            let used = TX_LEAD_US
                + TX_SETUP_US
                + PLL_SETTLE_US
                + airtime_us(frame, mode.bit_rate_bps())
                + TAIL_GUARD_US;
            assert!(
                used <= mode.slot_us(),
                "{mode:?}: {used} µs > {} µs",
                mode.slot_us()
            );
            // and one more byte would not fit (or the FIFO is the limit)
            let over = TX_LEAD_US
                + TX_SETUP_US
                + PLL_SETTLE_US
                + airtime_us(frame + 1, mode.bit_rate_bps())
                + TAIL_GUARD_US;
            assert!(over > mode.slot_us() || frame == FIFO_BYTES);
        }
    }

    #[test]
    fn frame_capacities() {
        assert_eq!(RateMode::L50.max_frame_bytes(), 32);
        assert_eq!(RateMode::M100.max_frame_bytes(), 54);
        assert_eq!(RateMode::F250.max_frame_bytes(), 41);
        assert_eq!(RateMode::F500.max_frame_bytes(), 32);
    }

    #[test]
    fn codes_round_trip() {
        for mode in RateMode::ALL {
            assert_eq!(RateMode::from_code(mode.code()), Some(mode));
        }
        assert_eq!(RateMode::from_code(4), None);
    }
}
