//! Flying on after a reset in the air (ArduPilot resumes after an in-flight watchdog reset;
//! a reset was a crash here). What the firmware keeps in RAM the reset start-up code does not
//! clear (a no-init section), as words this module encodes, checks and decodes:
//!
//! - the **flight state** ([`FlightState`], [`STATE_WORDS`]): armed and in the air, failsafe,
//!   the flight mode, the learnt hover throttle, the attitude and gyro bias — refreshed by
//!   the loop at least every [`STATE_REFRESH_MS`];
//! - the **gains** ([`GAINS_WORDS`]): the live settings (the flash record's encoding) and the
//!   three axes' Riccati solutions, written whenever the loop gets new ones — a resume
//!   rebuilds the controllers from them (`crate::gains::rebuild`), no design;
//! - the **fault** ([`FAULT_WORDS`]): what the panic or HardFault handler adds before its
//!   reset — the reason, the time, the faulting address;
//! - the **feed** ([`FEED_WORDS`]): the time of the supervisor's last watchdog feed.
//!
//! Each block carries a magic word and a CRC-32 (the flash record's), so RAM that held
//! anything else — a power-up's random contents — never decodes. [`plan`] decides at boot:
//! only after a watchdog or software (handler) reset, only from a record that says "armed,
//! in the air", and only if it is fresh — written at most [`FRESH_MS`] before the reset. The
//! reset's time is the handler's stamp, or after a watchdog reset the last feed plus the
//! IWDG's longest timeout (its slowest LSI): a bound, never an underestimate. The firmware
//! clears the record's magic words at once, so a record resumes one boot at most. The loop's
//! side hands out the flight state (`LoopSide::resume_state_due`), the app the gains
//! ([`FlightApp::keep_resume_gains`]).
//!
//! The resumed flight ([`FlightApp::resume`]) starts in failsafe with the recorded gains,
//! mode, hover throttle and attitude: the motors run again as soon as the IMU delivers,
//! without waiting for the link, and the link then decides (`Supervisor::resume`): the arm
//! switch on — or no arm switch set — is armed in the recorded mode, off is disarmed, a link
//! that does not come back is the failsafe as usual.

use crate::control::design::AxisDesign;
pub use crate::loop_side::STATE_REFRESH_MS;
pub use crate::pipeline::flight_state::{FlightState, STATE_WORDS};
use crate::pipeline::flight_state::{open, seal};
use crate::pipeline::from_settings;
use crate::settings::{RECORD_MAX, Settings, decode_record, record};

use super::FlightApp;
use super::watchdog::{IWDG, LSI_MIN_HZ};

/// A record is fresh when it was written at most this long before the reset, ms.
pub const FRESH_MS: u32 = 1_000;

const GAINS_MAGIC: u32 = 0x5447_4E31; // "TGN1"
const FAULT_MAGIC: u32 = 0x5446_4C31; // "TFL1"

/// Words of the fault block: magic, reason, time, address, CRC.
pub const FAULT_WORDS: usize = 5;
/// Words of the feed block: the time and its complement.
pub const FEED_WORDS: usize = 2;
/// Words of the gains block: magic, record length, the settings record, three axes' designs
/// (8 f64 and 3 iteration counts each), CRC.
pub const GAINS_WORDS: usize = 2 + RECORD_MAX.div_ceil(4) + 3 * (16 + 3) + 1;

/// What reset the MCU, from its reset flags (RCC_CSR on the F405).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ResetCause {
    /// Power-on or brown-out: RAM holds nothing.
    PowerOn,
    /// The reset pin (a button, a debugger).
    Pin,
    /// The independent watchdog.
    Watchdog,
    /// The firmware's own reset request (the panic and HardFault handlers).
    Software,
    /// Anything else (the window watchdog, low-power management).
    Other,
}

/// Why a fault handler reset the board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FaultReason {
    /// A Rust panic.
    Panic,
    /// A HardFault (a fault no handler took, escalated).
    HardFault,
}

/// A fault handler's record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fault {
    /// What happened.
    pub reason: FaultReason,
    /// The board's clock at the fault, ms.
    pub at_ms: u32,
    /// The faulting instruction's address (HardFault), or the panic handler's return
    /// address (inside core's panic entry).
    pub address: u32,
}

/// What a resumed flight starts from.
#[derive(Debug, Clone, PartialEq)]
pub struct Resume {
    /// The loop's state at the reset.
    pub state: FlightState,
    /// The live settings then.
    pub settings: Settings,
    /// The axes' Riccati solutions then.
    pub designs: [AxisDesign; 3],
    /// The fault that reset the board, if a handler recorded one.
    pub fault: Option<Fault>,
}

/// Why a record does not resume.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ColdBoot {
    /// Power-on, the reset pin or another cause: a normal boot.
    NotAFaultReset,
    /// No valid flight state (never written, or the CRC fails: power-up RAM).
    NoState,
    /// The frame was disarmed or on the ground.
    NotInTheAir,
    /// Written longer than [`FRESH_MS`] before the reset (or the reset's time unknown).
    Stale,
    /// No valid gains record, or settings that no longer make a setup.
    NoGains,
}

impl Fault {
    /// The block a fault handler writes.
    pub fn encode(&self) -> [u32; FAULT_WORDS] {
        let reason = match self.reason {
            FaultReason::Panic => 1,
            FaultReason::HardFault => 2,
        };
        let mut words = [FAULT_MAGIC, reason, self.at_ms, self.address, 0];
        seal(&mut words);
        words
    }

    /// The fault a block holds, if its magic and CRC check.
    pub fn decode(block: &[u32; FAULT_WORDS]) -> Option<Self> {
        let [_, reason, at_ms, address] = *open(block, FAULT_MAGIC)? else {
            return None;
        };
        let reason = match reason {
            1 => FaultReason::Panic,
            2 => FaultReason::HardFault,
            _ => return None,
        };
        Some(Self {
            reason,
            at_ms,
            address,
        })
    }
}

/// The feed block for a feed at `now_ms`.
pub const fn encode_feed(now_ms: u32) -> [u32; FEED_WORDS] {
    [now_ms, !now_ms]
}

/// The last feed's time, if the block is whole.
pub fn decode_feed(block: &[u32; FEED_WORDS]) -> Option<u32> {
    let [t, check] = *block;
    (check == !t).then_some(t)
}

/// The gains block for `settings` (live) and the controllers' `designs`; `None` only if
/// the settings record does not fit (ruled out by its bound).
pub fn encode_gains(settings: &Settings, designs: &[AxisDesign; 3]) -> Option<[u32; GAINS_WORDS]> {
    let bytes = record(settings, 0).ok()?;
    let mut words = [0u32; GAINS_WORDS];
    let (head, rest) = words.split_at_mut(2);
    head.copy_from_slice(&[GAINS_MAGIC, u32::try_from(bytes.len()).ok()?]);
    let (packed, rest) = rest.split_at_mut(RECORD_MAX.div_ceil(4));
    for (word, chunk) in packed.iter_mut().zip(bytes.chunks(4)) {
        let mut b = [0u8; 4];
        for (d, s) in b.iter_mut().zip(chunk) {
            *d = *s;
        }
        *word = u32::from_le_bytes(b);
    }
    let (gains, counts) = rest.split_at_mut(3 * 16);
    let (mut pairs, mut counts) = (gains.chunks_exact_mut(2), counts.iter_mut());
    // Each design's values drive the zips, so no pair or count word is skipped.
    for d in designs {
        for (v, pair) in gains_of(d).into_iter().zip(pairs.by_ref()) {
            let bits = v.to_bits();
            pair.copy_from_slice(&[bits as u32, (bits >> 32) as u32]);
        }
        for (n, word) in d.iterations.into_iter().zip(counts.by_ref()) {
            *word = n;
        }
    }
    seal(&mut words);
    Some(words)
}

/// A design's gains in the block's order: Kalman, rate, attitude.
fn gains_of(d: &AxisDesign) -> [f64; 8] {
    let ([k0, k1, k2], [r0, r1], [a0, a1, a2]) = (d.kalman, d.rate, d.attitude);
    [k0, k1, k2, r0, r1, a0, a1, a2]
}

/// The design [`gains_of`] lists, with its doubling steps.
fn design_of(gains: [f64; 8], iterations: [u32; 3]) -> AxisDesign {
    let [k0, k1, k2, r0, r1, a0, a1, a2] = gains;
    AxisDesign {
        kalman: [k0, k1, k2],
        rate: [r0, r1],
        attitude: [a0, a1, a2],
        iterations,
    }
}

/// The settings and designs a gains block holds, if its magic, CRC and settings record
/// check.
pub fn decode_gains(block: &[u32; GAINS_WORDS]) -> Option<(Settings, [AxisDesign; 3])> {
    let body = open(block, GAINS_MAGIC)?;
    let (&len, rest) = body.get(1..)?.split_first()?;
    let (packed, rest) = rest.split_at_checked(RECORD_MAX.div_ceil(4))?;
    let mut bytes = [0u8; 4 * RECORD_MAX.div_ceil(4)];
    for (chunk, word) in bytes.chunks_exact_mut(4).zip(packed) {
        chunk.copy_from_slice(&word.to_le_bytes());
    }
    let record = decode_record(bytes.get(..usize::try_from(len).ok()?)?)?;
    if record.refused > 0 {
        return None;
    }
    let (gains, counts) = rest.split_at_checked(3 * 16)?;
    let mut values = gains.chunks_exact(2).map(|p| match *p {
        [lo, hi] => f64::from_bits(u64::from(lo) | u64::from(hi) << 32),
        _ => f64::NAN,
    });
    let mut counts = counts.iter().copied();
    let designs = [(); 3].map(|()| {
        let (mut gains, mut iterations) = ([f64::NAN; 8], [0; 3]);
        for (slot, v) in gains.iter_mut().zip(values.by_ref()) {
            *slot = v;
        }
        for (slot, n) in iterations.iter_mut().zip(counts.by_ref()) {
            *slot = n;
        }
        design_of(gains, iterations)
    });
    Some((record.settings, designs))
}

/// What a board's start-up found in its no-init record.
#[derive(Debug, Clone, Copy)]
pub struct Kept<'a> {
    /// The flight-state block.
    pub state: &'a [u32; STATE_WORDS],
    /// The gains block.
    pub gains: &'a [u32; GAINS_WORDS],
    /// The fault block.
    pub fault: &'a [u32; FAULT_WORDS],
    /// The feed block.
    pub feed: &'a [u32; FEED_WORDS],
}

/// The boot's decision: resume the flight the record describes, or why not.
pub fn plan(cause: ResetCause, kept: &Kept<'_>) -> Result<Resume, ColdBoot> {
    if !matches!(cause, ResetCause::Watchdog | ResetCause::Software) {
        return Err(ColdBoot::NotAFaultReset);
    }
    let state = FlightState::decode(kept.state).ok_or(ColdBoot::NoState)?;
    if !(state.armed && state.in_air) {
        return Err(ColdBoot::NotInTheAir);
    }
    let fault = Fault::decode(kept.fault);
    // The reset's time: the handler's stamp, else the last feed plus the longest the IWDG
    // can take (at the slowest LSI). Unknown is stale.
    let reset_ms = match (cause, fault) {
        (ResetCause::Software, Some(f)) => Some(f.at_ms),
        (ResetCause::Watchdog, _) => {
            decode_feed(kept.feed).map(|t| t.wrapping_add(IWDG.timeout_ms(LSI_MIN_HZ)))
        }
        _ => None,
    };
    let age_ms = reset_ms.map(|t| t.wrapping_sub(state.written_ms));
    if age_ms.is_none_or(|a| a > FRESH_MS) {
        return Err(ColdBoot::Stale);
    }
    let (settings, designs) = decode_gains(kept.gains).ok_or(ColdBoot::NoGains)?;
    if from_settings(&settings).is_err() {
        return Err(ColdBoot::NoGains);
    }
    Ok(Resume {
        state,
        settings,
        designs,
        fault: fault.filter(|_| cause == ResetCause::Software),
    })
}

impl FlightApp {
    /// The application booting at `now_ms` into a flight resumed after a reset in the air
    /// ([`plan`]): `stored` is what flash holds, the live settings, gains and loop state are
    /// the record's, and the loop flies in failsafe until the link decides
    /// (`Supervisor::resume`). `None` if the record's settings make no setup.
    pub fn resume(stored: Settings, resume: &Resume, now_ms: u32) -> Option<Self> {
        let setup = from_settings(&resume.settings).ok()?;
        let controllers = crate::gains::rebuild(&setup.control, resume.designs);
        Self::with_setup(
            stored,
            resume.settings.clone(),
            (setup, None),
            Some(controllers),
            now_ms,
            Some(resume),
        )
    }

    /// How this boot started: `Some` after a resumed flight (with the fault that reset the
    /// board, if a handler recorded one).
    pub fn resumed(&self) -> Option<Option<Fault>> {
        self.resumed
    }

    /// Writes the gains block into `out` if the loop's gains changed since it was last
    /// written (at boot, after a new design is installed); whether it did.
    pub fn keep_resume_gains(&mut self, out: &mut [u32; GAINS_WORDS]) -> bool {
        if !self.gains_changed {
            return false;
        }
        let Some(designs) = self.designs else {
            return false;
        };
        self.gains_changed = false;
        match encode_gains(&self.flown, &designs) {
            Some(words) => {
                *out = words;
                true
            }
            None => false,
        }
    }
}

#[cfg(test)]
#[path = "resume_tests.rs"]
mod tests;
