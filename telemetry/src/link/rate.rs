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
/// Everything the chip adds around our frame (in the modes that send the hardware header;
/// [`RateMode::chip_overhead_bytes`] gives each mode's).
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
/// adds with the hardware header (preamble, sync, header, length, chip CRC), in µs, rounded
/// up. [`RateMode::airtime_us`] is the mode-aware form (F700 sends no hardware header).
pub const fn airtime_us(frame_bytes: usize, bit_rate_bps: u32) -> u32 {
    on_air_us(frame_bytes + CHIP_OVERHEAD_BYTES, bit_rate_bps)
}

/// Airtime of `bytes` on air at `bit_rate_bps`, µs, rounded up.
const fn on_air_us(bytes: usize, bit_rate_bps: u32) -> u32 {
    let bits = (bytes * 8) as u64;
    let rate = bit_rate_bps as u64;
    (bits * 1_000_000).div_ceil(rate) as u32
}

/// F700's slot: 1 428 µs, 700 slots/s. At 1:8 telemetry that is 612.5 uplinks/s, each with
/// the four sticks (spec §4.1 derives it).
const F700_SLOT_US: u32 = 1_428;
/// F700's TX lead. The follower opens its window [`RX_EARLY_US`] before the slot anyway, so
/// the lead only has to cover building the frame and the hop-register write (channels are
/// latched once the transmitter is on, `link::master::uplink_latch_offset_us`).
///
/// [`RX_EARLY_US`]: crate::link::core::follower::RX_EARLY_US
const F700_TX_LEAD_US: u32 = 30;
/// F700's SPI set-up: its largest frame is 21 bytes, 11 fewer than F500's 32 (≈ 17 µs less
/// FIFO burst at 5.25 MHz); measured by radio-rfm22b's
/// `transmit_set_up_on_the_spi_bus_fits_the_link_budget`.
const F700_TX_SETUP_US: u32 = 80;
/// F700's tail guard, what is left of its slot (the other modes keep 150 µs): the receiver
/// drains a 21-byte FIFO and the sender of the next slot turns around. After a downlink slot
/// the master must have read the follower's frame — which ends late by the follower's own
/// read-out, since it re-times its grid when its read ends — before its next uplink.
const F700_TAIL_GUARD_US: u32 = 149;

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
    /// 700 slots/s at 256 kbps: the stick mode. Four sticks (11 bit) in every uplink, the
    /// twelve aux channels three at a time round-robin ([`ChannelFormat::Sticks16`]), no
    /// hardware header (the keyed link CRC is the identity check), tighter turnarounds.
    ///
    /// [`ChannelFormat::Sticks16`]: crate::channels::ChannelFormat::Sticks16
    F700,
}

impl RateMode {
    /// All modes, slowest first.
    pub const ALL: [RateMode; 5] = [
        RateMode::L50,
        RateMode::M100,
        RateMode::F250,
        RateMode::F500,
        RateMode::F700,
    ];

    /// Air bit rate.
    pub const fn bit_rate_bps(self) -> u32 {
        match self {
            RateMode::L50 => 19_200,
            RateMode::M100 => 57_600,
            RateMode::F250 => 128_000,
            RateMode::F500 | RateMode::F700 => 256_000,
        }
    }

    /// Slot length: the packet period.
    pub const fn slot_us(self) -> u32 {
        match self {
            RateMode::L50 => 20_000,
            RateMode::M100 => 10_000,
            RateMode::F250 => 4_000,
            RateMode::F500 => 2_000,
            RateMode::F700 => F700_SLOT_US,
        }
    }

    /// Slots per second.
    pub const fn slot_rate_hz(self) -> u32 {
        1_000_000 / self.slot_us()
    }

    /// How long the sender waits after its slot starts before it sends ([`TX_LEAD_US`]; F700
    /// 30 µs).
    pub const fn tx_lead_us(self) -> u32 {
        match self {
            RateMode::F700 => F700_TX_LEAD_US,
            _ => TX_LEAD_US,
        }
    }

    /// SPI set-up charged to the sender ([`TX_SETUP_US`]; F700 80 µs for its smaller frame).
    pub const fn tx_setup_us(self) -> u32 {
        match self {
            RateMode::F700 => F700_TX_SETUP_US,
            _ => TX_SETUP_US,
        }
    }

    /// Time kept free at the end of the slot ([`TAIL_GUARD_US`]; F700 149 µs).
    pub const fn tail_guard_us(self) -> u32 {
        match self {
            RateMode::F700 => F700_TAIL_GUARD_US,
            _ => TAIL_GUARD_US,
        }
    }

    /// Hardware header bytes sent: [`HEADER_BYTES`], or none at F700, where the keyed link
    /// CRC (spec §5.3) is the only identity check: the 4 bytes would cost 125 µs per packet
    /// to repeat what that CRC already proves, and drop foreign packets a little earlier.
    pub const fn chip_header_bytes(self) -> usize {
        match self {
            RateMode::F700 => 0,
            _ => HEADER_BYTES,
        }
    }

    /// Everything the chip adds around our frame in this mode.
    pub const fn chip_overhead_bytes(self) -> usize {
        PREAMBLE_BYTES + SYNC_BYTES + self.chip_header_bytes() + LENGTH_BYTES + CHIP_CRC_BYTES
    }

    /// The airtime of `frame_bytes` of our frame in this mode, chip overhead included, µs.
    pub const fn airtime_us(self, frame_bytes: usize) -> u32 {
        on_air_us(
            frame_bytes + self.chip_overhead_bytes(),
            self.bit_rate_bps(),
        )
    }

    /// Lead, SPI set-up, PLL settle and tail guard: the part of a slot that is not packet.
    pub const fn slot_overhead_us(self) -> u32 {
        self.tx_lead_us() + self.tx_setup_us() + PLL_SETTLE_US + self.tail_guard_us()
    }

    /// Airtime left for one packet once lead, SPI set-up, PLL settle and tail guard are paid.
    pub const fn packet_budget_us(self) -> u32 {
        self.slot_us() - self.slot_overhead_us()
    }

    /// The largest frame (our bytes, excluding the chip's) that fits the slot and the FIFO.
    pub const fn max_frame_bytes(self) -> usize {
        let budget_bits = self.packet_budget_us() as u64 * self.bit_rate_bps() as u64 / 1_000_000;
        let on_air = (budget_bits / 8) as usize;
        let frame = on_air.saturating_sub(self.chip_overhead_bytes());
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
            RateMode::F700 => 4,
        }
    }

    /// Inverse of [`RateMode::code`].
    pub const fn from_code(code: u8) -> Option<RateMode> {
        match code {
            0 => Some(RateMode::L50),
            1 => Some(RateMode::M100),
            2 => Some(RateMode::F250),
            3 => Some(RateMode::F500),
            4 => Some(RateMode::F700),
            _ => None,
        }
    }

    /// The Si4432's sensitivity at the mode's bit rate, whole dBm: −121 dBm at 2.4 kbps
    /// (datasheet, GFSK, BER 10⁻³) worse by 10·log10 of the bit rate over it (the noise
    /// bandwidth grows with it), as the simulators model it (`telemetry::mock`,
    /// `si4432-sim`'s `propagation`). The dynamic power's margins are over this.
    pub const fn sensitivity_dbm(self) -> i16 {
        match self {
            RateMode::L50 => -112,
            RateMode::M100 => -107,
            RateMode::F250 => -104,
            RateMode::F500 | RateMode::F700 => -101,
        }
    }

    /// The mode's name, as the handset's Packet Rate row, the settings text and the tools'
    /// command lines spell it.
    pub const fn name(self) -> &'static str {
        match self {
            RateMode::L50 => "L50",
            RateMode::M100 => "M100",
            RateMode::F250 => "F250",
            RateMode::F500 => "F500",
            RateMode::F700 => "F700",
        }
    }
}

impl core::fmt::Display for RateMode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is no rate mode ([`RateMode`]'s `FromStr`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UnknownRateMode;

impl core::fmt::Display for UnknownRateMode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("not a rate mode (L50, M100, F250, F500 or F700)")
    }
}

impl core::error::Error for UnknownRateMode {}

impl core::str::FromStr for RateMode {
    type Err = UnknownRateMode;

    /// A mode by its [`RateMode::name`], in any letter case (`f500` is `F500`).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        RateMode::ALL
            .into_iter()
            .find(|mode| mode.name().eq_ignore_ascii_case(s))
            .ok_or(UnknownRateMode)
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
            let used = mode.tx_lead_us()
                + mode.tx_setup_us()
                + PLL_SETTLE_US
                + mode.airtime_us(frame)
                + mode.tail_guard_us();
            assert!(
                used <= mode.slot_us(),
                "{mode:?}: {used} µs > {} µs",
                mode.slot_us()
            );
            // and one more byte would not fit (or the FIFO is the limit)
            let over = mode.tx_lead_us()
                + mode.tx_setup_us()
                + PLL_SETTLE_US
                + mode.airtime_us(frame + 1)
                + mode.tail_guard_us();
            assert!(over > mode.slot_us() || frame == FIFO_BYTES);
        }
    }

    #[test]
    fn frame_capacities() {
        assert_eq!(RateMode::L50.max_frame_bytes(), 32);
        assert_eq!(RateMode::M100.max_frame_bytes(), 54);
        assert_eq!(RateMode::F250.max_frame_bytes(), 41);
        assert_eq!(RateMode::F500.max_frame_bytes(), 32);
        assert_eq!(RateMode::F700.max_frame_bytes(), 21);
    }

    #[test]
    fn the_old_modes_keep_their_timing() {
        for mode in [
            RateMode::L50,
            RateMode::M100,
            RateMode::F250,
            RateMode::F500,
        ] {
            assert_eq!(mode.slot_overhead_us(), 550);
            assert_eq!(mode.chip_overhead_bytes(), CHIP_OVERHEAD_BYTES);
            assert_eq!(mode.airtime_us(29), airtime_us(29, mode.bit_rate_bps()));
        }
    }

    #[test]
    fn f700_is_header_less_and_fits_the_stick_uplink_and_12_bytes_of_downlink() {
        let mode = RateMode::F700;
        assert_eq!(mode.slot_rate_hz(), 700);
        assert_eq!(mode.chip_overhead_bytes(), 10);
        // 21-byte frame + 10 chip bytes = 31 bytes = 968.75 µs
        assert_eq!(mode.airtime_us(21), 969);
        assert_eq!(mode.slot_overhead_us(), 459);
        // An uplink of 5 header + 10 channel + 2 CRC bytes leaves 4 for the stream (2 with a
        // report); a downlink (header, report, CRC: 9 bytes) carries 12 stream bytes.
        assert_eq!(mode.max_frame_bytes() - 17, 4);
        assert_eq!(mode.max_frame_bytes() - 9, 12);
    }

    #[test]
    fn codes_round_trip() {
        for mode in RateMode::ALL {
            assert_eq!(RateMode::from_code(mode.code()), Some(mode));
            assert_eq!(mode.to_string().parse(), Ok(mode));
            assert_eq!(mode.name().to_ascii_lowercase().parse(), Ok(mode));
        }
        assert_eq!(RateMode::from_code(5), None);
        assert_eq!("F1000".parse::<RateMode>(), Err(UnknownRateMode));
        assert_eq!("".parse::<RateMode>(), Err(UnknownRateMode));
    }
}
