//! The record of every frame put on air and what each other radio made of it.

use core::time::Duration;

use crate::modem::Mismatch;

/// Index of a radio in its medium (the order of `Medium::add_radio` calls).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RadioId(pub usize);

/// What one receiver made of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// Valid packet: header, length and CRC (if enabled) passed; `ipkvalid` raised.
    Delivered {
        /// Bits flipped by noise/interference that the CRC did not need to catch.
        bit_errors: u32,
    },
    /// Received to the end but the CRC failed; `icrcerror` raised.
    CrcError {
        /// Bits flipped by noise/interference.
        bit_errors: u32,
    },
    /// The receiver was not in RX (or not yet settled) when the preamble went by.
    NotListening,
    /// Modem settings do not match (frequency, bit rate, deviation, modulation).
    Mismatch(Mismatch),
    /// Signal more than 6 dB below sensitivity.
    TooWeak,
    /// Dropped by the medium's random packet loss.
    RandomLoss,
    /// The receiver was already busy with another frame.
    Busy,
    /// The receiver started listening too late to detect the preamble.
    MissedPreamble,
    /// The receiver's sync word does not occur in the transmitted sync word.
    SyncMismatch,
    /// Bit errors corrupted the sync word.
    SyncCorrupted,
    /// The header failed the receiver's check (0x32, 0x3F–0x46).
    HeaderMismatch,
    /// A stronger frame captured the receiver before sync.
    Captured,
    /// The receiver left RX (or was reset) before the frame ended.
    Aborted,
    /// The transmitter sent no packet data (unmodulated, direct or PN9 mode).
    NoData,
}

/// One receiver's view of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reception {
    /// The receiving radio.
    pub radio: RadioId,
    /// Signal power at this receiver, in dBm.
    pub power_dbm: f64,
    /// What happened.
    pub outcome: Outcome,
}

/// One frame on air.
#[derive(Clone, Debug, PartialEq)]
pub struct TraceFrame {
    /// Sequence number (0, 1, 2 … in start order).
    pub id: u64,
    /// The transmitting radio.
    pub radio: RadioId,
    /// Start of the preamble.
    pub start: Duration,
    /// End of the last bit (or of the abort). `Duration::MAX` while a carrier is still on.
    pub end: Duration,
    /// Carrier frequency as radiated (including crystal error), in Hz.
    pub carrier_hz: f64,
    /// Bit rate, in bit/s.
    pub bit_rate_bps: f64,
    /// Transmit power, in dBm.
    pub tx_power_dbm: f64,
    /// The frame after the preamble as the packet handler built it (sync, header, length,
    /// payload, CRC), before whitening.
    pub bytes: Vec<u8>,
    /// True when the transmitter aborted the frame or ran its FIFO dry.
    pub damaged: bool,
    /// Power of this frame at every radio (index = `RadioId.0`; the sender's own entry
    /// included), in dBm.
    pub power_dbm: Vec<f64>,
    /// Every other radio's outcome, in radio order of first decision.
    pub receptions: Vec<Reception>,
}

impl TraceFrame {
    /// The outcome at `radio`, if it was recorded.
    pub fn outcome_at(&self, radio: RadioId) -> Option<Outcome> {
        self.receptions
            .iter()
            .find(|r| r.radio == radio)
            .map(|r| r.outcome)
    }

    /// Airtime (end − start).
    pub fn airtime(&self) -> Duration {
        self.end.saturating_sub(self.start)
    }
}

impl core::fmt::Display for TraceFrame {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "#{} t={:.6}s {:.4}MHz radio{} {}B",
            self.id,
            self.start.as_secs_f64(),
            self.carrier_hz / 1e6,
            self.radio.0,
            self.bytes.len()
        )?;
        for r in &self.receptions {
            write!(
                f,
                " | radio{} {:.1}dBm {:?}",
                r.radio.0, r.power_dbm, r.outcome
            )?;
        }
        Ok(())
    }
}
