//! What the link needs from a radio and a clock. The protocol owns these traits (as
//! lorawan-device owns its radio trait); the RFM22b driver, the packet-level mock and the
//! chip simulator implement them. Async fns in traits: the loops are generic, never `dyn`.
#![allow(async_fn_in_trait)]

use super::rate::RateMode;

/// Radio setup for one link phase (bind or bound).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RadioConfig {
    /// Modem profile (bit rate, deviation, filter) to load.
    pub rate: RateMode,
    /// Hardware header: sent on TX (Si4432 0x3A–0x3D) and required on RX (0x3F–0x42, all
    /// bits checked, broadcast off), so packets of other links never reach the FIFO.
    pub header: [u8; 4],
    /// Carrier of channel 0 (Si4432 0x75–0x77).
    pub base_hz: u32,
    /// Channel spacing, a multiple of 10 kHz (Si4432 0x7A).
    pub spacing_hz: u32,
    /// Transmit at the radio's lowest power step instead of the configured one: set in
    /// bind mode, so a bind is only made (or overheard, or spoofed) at close range.
    pub reduced_power: bool,
}

impl RadioConfig {
    /// Frequency of `channel`.
    pub const fn channel_hz(&self, channel: u8) -> u32 {
        self.base_hz + channel as u32 * self.spacing_hz
    }
}

/// What one listen window gave the link ([`PacketRadio::receive`]).
///
/// Two layers, two types: a chip driver has its own, richer result (radio-rfm22b's
/// `RxOutcome`: the received header, raw RSSI and AFC offset, a CRC error told from an
/// over-long packet), and its `telemetry` adapter maps that to this one. They stay two because
/// the driver is used without this crate (OpenLRSng, other protocols) and the link must not
/// depend on one chip: the link needs only the length, the RSSI, and whether something
/// corrupt arrived (to count it and listen on).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkRx {
    /// A packet passed the chip's checks; `len` bytes are in the buffer.
    Packet {
        /// Packet length.
        len: usize,
        /// RSSI latched at sync-word detection, dBm.
        rssi_dbm: i16,
    },
    /// A packet arrived but failed the chip's own checks (CRC, length); the radio returns
    /// early so the caller can count it and listen on for the rest of its window.
    Corrupted,
    /// Nothing valid arrived before the timeout.
    Timeout,
}

/// A half-duplex packet radio.
pub trait PacketRadio {
    /// The radio's own error (bus failure, chip lost its registers, …).
    type Error: core::fmt::Debug;

    /// Loads the modem profile and header for `config`.
    async fn configure(&mut self, config: &RadioConfig) -> Result<(), Self::Error>;

    /// Tunes to `channel` of the configured grid (the Si4432 hop register 0x79; takes effect
    /// for the next transmit or receive).
    async fn set_channel(&mut self, channel: u8) -> Result<(), Self::Error>;

    /// Sends one packet; returns when it has left the antenna.
    async fn transmit(&mut self, frame: &[u8]) -> Result<(), Self::Error>;

    /// Starts a packet of `len` bytes whose bytes are not known yet: the transmitter comes
    /// on now, the PLL settles and preamble and sync go on the air while the caller latches
    /// its input, builds the frame and hands it to [`PacketRadio::finish_transmit`] — at
    /// the latest by the end of the sync word (+ header and length; 250 µs at 256 kbps),
    /// when the chip needs the first byte (the Si4432 takes each payload byte from its FIFO
    /// when it is due; one loaded too late goes out wrong and fails the CRC, never a wrong
    /// frame).
    async fn begin_transmit(&mut self, len: usize) -> Result<(), Self::Error>;

    /// The bytes of the packet [`PacketRadio::begin_transmit`] started (exactly `len` of
    /// them); returns when it has left the antenna.
    async fn finish_transmit(&mut self, frame: &[u8]) -> Result<(), Self::Error>;

    /// Listens for one packet for up to `timeout_us`; returns as soon as one has fully
    /// arrived (the caller timestamps it with its clock).
    async fn receive(&mut self, buf: &mut [u8], timeout_us: u32) -> Result<LinkRx, Self::Error>;

    /// Sets the transmit power to `step` of the radio's eight (0 lowest … 7 highest; the
    /// RFM22B's +1 … +20 dBm), from the next transmission on and kept across a
    /// [`PacketRadio::recover`]; the loops call it between slots when the state machine's
    /// [`tx_power`](crate::link::core::Master::tx_power) changes (dynamic power,
    /// `link::power`). Default: a radio without power control ignores it.
    async fn set_tx_power(&mut self, step: u8) -> Result<(), Self::Error> {
        let _ = step;
        Ok(())
    }

    /// Checks that the chip still holds its setup (the link loops call it every
    /// `HEALTH_CHECK_PERIOD_US`); an error (e.g. the chip had reset) makes the loop
    /// [`PacketRadio::recover`]. Default: nothing to check.
    async fn check_health(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }

    /// Brings the radio back after an error: set `config` up again from scratch, even if it
    /// believes it is already configured. Default: [`PacketRadio::configure`].
    async fn recover(&mut self, config: &RadioConfig) -> Result<(), Self::Error> {
        self.configure(config).await
    }
}

/// Microsecond time base shared by a link end (embassy-time on hardware, virtual in tests).
pub trait LinkClock {
    /// Microseconds since an arbitrary epoch; monotonic.
    fn now_us(&self) -> u64;

    /// Sleeps until `deadline_us` (returns at once if it has passed).
    async fn sleep_until_us(&mut self, deadline_us: u64);
}
