//! The loop's state kept across a reset in the air ([`FlightState`]), as a sealed block of
//! words: the loop hands it out and resumes from it; the application's `app::resume` keeps
//! it with the other blocks, sealed the same way ([`seal`], [`open`]).

use crate::estimation::quaternion::Quaternion;
use crate::settings::crc32_words;
use crate::supervisor::FlightMode;

const STATE_MAGIC: u32 = 0x5453_5431; // "TST1"

/// Words of the flight-state block: magic, time, flags and mode, hover throttle, attitude
/// (4), gyro bias (3), CRC.
pub const STATE_WORDS: usize = 12;

/// The loop's state worth keeping across a reset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightState {
    /// The board's clock when it was written, ms.
    pub written_ms: u32,
    /// Motors may turn.
    pub armed: bool,
    /// The touchdown detector had the frame in the air.
    pub in_air: bool,
    /// In the link failsafe.
    pub failsafe: bool,
    /// The flight mode flown.
    pub mode: FlightMode,
    /// The learnt hover throttle.
    pub hover_throttle: f32,
    /// Body → NED attitude.
    pub attitude: Quaternion,
    /// The attitude filter's gyro bias, rad/s.
    pub gyro_bias_radps: [f32; 3],
}

/// Seals a block: its last word becomes the CRC of the others.
pub fn seal(block: &mut [u32]) {
    if let Some((crc, body)) = block.split_last_mut() {
        *crc = crc32_words(body);
    }
}

/// The block's body if its magic and CRC hold.
pub fn open(block: &[u32], magic: u32) -> Option<&[u32]> {
    let (crc, body) = block.split_last()?;
    (body.first() == Some(&magic) && crc32_words(body) == *crc).then_some(body)
}

impl FlightState {
    /// The block the firmware keeps.
    pub fn encode(&self) -> [u32; STATE_WORDS] {
        let flags = u32::from(self.armed)
            | u32::from(self.in_air) << 1
            | u32::from(self.failsafe) << 2
            | u32::from(self.mode.id()) << 8;
        let [w, x, y, z] = self.attitude.map(f32::to_bits);
        let [bx, by, bz] = self.gyro_bias_radps.map(f32::to_bits);
        let mut words = [
            STATE_MAGIC,
            self.written_ms,
            flags,
            self.hover_throttle.to_bits(),
            w,
            x,
            y,
            z,
            bx,
            by,
            bz,
            0,
        ];
        seal(&mut words);
        words
    }

    /// The state a block holds, if its magic and CRC check.
    pub fn decode(block: &[u32; STATE_WORDS]) -> Option<Self> {
        let [_, written_ms, flags, hover, w, x, y, z, bx, by, bz] = *open(block, STATE_MAGIC)?
        else {
            return None;
        };
        let mode = u8::try_from(flags >> 8)
            .ok()
            .and_then(FlightMode::from_id)?;
        Some(Self {
            written_ms,
            armed: flags & 1 != 0,
            in_air: flags & 2 != 0,
            failsafe: flags & 4 != 0,
            mode,
            hover_throttle: f32::from_bits(hover),
            attitude: [w, x, y, z].map(f32::from_bits),
            gyro_bias_radps: [bx, by, bz].map(f32::from_bits),
        })
    }
}
