//! The module's settings and their on-flash record.
//!
//! The record is one versioned, fixed-size byte string stored under one key, so a save is
//! a single sequential-storage item write: after a power cut the map holds either the old
//! or the new record (the item CRC rejects a torn write), never a mix of fields.
//!
//! Record layout (version 2, 14 bytes; input 0 PPM, 1 CRSF 400 kBd, 2 CRSF 115 200 Bd;
//! failsafe 0 hold last, 1 stop pulses): `[2, role, rate, input, output, band, tx_power,
//! failsafe, bind_id (u32 LE), input_timeout_ms (u16 LE)]`. Version 1 (12 bytes, up to
//! `bind_id`) still loads, with the default input timeout; every stored field keeps its
//! meaning (a stored "hold last" stays hold last, only the default changed). Every byte is
//! checked on decode; an unknown value is an error, never a guess.

pub mod store;
pub mod text;

pub use store::{SettingsStore, StoreError};
pub use text::TextError;

use crate::ppm::FailsafeOutput;

/// Which end of the link the module is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Role {
    /// JR-bay transmitter: handset in, telemetry out.
    Transmitter,
    /// Receiver: link in, PPM out.
    Receiver,
}

/// Air data rate (the OpenLRSng modem profiles, radio.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RateMode {
    /// 4800 bit/s, longest range.
    Bps4800,
    /// 9600 bit/s.
    Bps9600,
    /// 19 200 bit/s (OpenLRSng default).
    Bps19200,
    /// 57 600 bit/s.
    Bps57600,
    /// 125 000 bit/s.
    Bps125000,
}

/// Where the channels come from in the transmitter role.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InputProtocol {
    /// PPM on JR pin 1.
    Ppm,
    /// CRSF on JR pin 5 (half duplex) at 400 kBd, EdgeTX's default.
    Crsf,
    /// CRSF at 115 200 Bd, for radios or cables that cannot run 400 kBd.
    Crsf115200,
}

impl InputProtocol {
    /// CRSF at either rate.
    pub const fn is_crsf(self) -> bool {
        matches!(self, InputProtocol::Crsf | InputProtocol::Crsf115200)
    }
}

/// What goes back to the handset on JR pin 5 (transmitter role).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OutputProtocol {
    /// Nothing.
    Off,
    /// CRSF telemetry frames (with CRSF input).
    Crsf,
    /// FrSky S.Port frames pushed unpolled at 57 600 Bd (protocols.md §1.3).
    SPort,
    /// FrSky D hub frames at 9600 Bd (older radios).
    FrskyHub,
}

/// Frequency band of the RFM22B build.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Band {
    /// 433 MHz ISM.
    Mhz433,
    /// 868 MHz SRD.
    Mhz868,
    /// 915 MHz ISM.
    Mhz915,
}

/// Everything the module remembers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// Transmitter or receiver.
    pub role: Role,
    /// Air data rate.
    pub rate: RateMode,
    /// Handset input.
    pub input: InputProtocol,
    /// Handset telemetry output.
    pub output: OutputProtocol,
    /// RF band.
    pub band: Band,
    /// RFM22B power step 0…7 (register 0x6D bits 2..0, radio.md).
    pub tx_power: u8,
    /// Failsafe behaviour of the PPM output (receiver role).
    pub failsafe: FailsafeOutput,
    /// Identity shared with the bound peer.
    pub bind_id: u32,
    /// Transmitter role: the handset input (PPM or CRSF) counts as lost after this long
    /// without a frame, ms ([`INPUT_TIMEOUT_MS`]); the link then tells the flight side to
    /// fly its failsafe instead of stale sticks.
    pub input_timeout_ms: u16,
}

/// Range and default of [`Settings::input_timeout_ms`]: never shorter than a few frames of
/// the slowest input (PPM 22.5 ms, CRSF at 50 Hz), never so long that stale sticks fly for
/// seconds.
pub const INPUT_TIMEOUT_MS: core::ops::RangeInclusive<u16> = 100..=2_000;
/// Factory input timeout: the flight side is in failsafe within 1 s of the input stopping.
pub const DEFAULT_INPUT_TIMEOUT_MS: u16 = 500;

impl Default for Settings {
    fn default() -> Self {
        Self {
            role: Role::Transmitter,
            rate: RateMode::Bps19200,
            input: InputProtocol::Ppm,
            output: OutputProtocol::SPort,
            band: Band::Mhz433,
            tx_power: 7,
            // Holding the last values would hold the throttle on a lost link.
            failsafe: FailsafeOutput::StopPulses,
            bind_id: 0,
            input_timeout_ms: DEFAULT_INPUT_TIMEOUT_MS,
        }
    }
}

/// Current record version.
pub const RECORD_VERSION: u8 = 2;
/// Record length of the current version.
pub const RECORD_LEN: usize = 14;
/// Record length of version 1 (no input timeout).
pub const RECORD_V1_LEN: usize = 12;

/// Why a record does not decode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// Wrong length for its version.
    Length {
        /// Bytes found.
        found: usize,
    },
    /// Unknown record version.
    Version {
        /// Version found.
        found: u8,
    },
    /// A field holds a value no writer of its version produces.
    Field {
        /// Byte offset of the field.
        offset: usize,
    },
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Length { found } => write!(f, "settings record of {found} bytes"),
            Self::Version { found } => write!(f, "settings record version {found}"),
            Self::Field { offset } => write!(f, "bad settings field at byte {offset}"),
        }
    }
}

impl core::error::Error for DecodeError {}

impl Settings {
    /// The current (version 2) record.
    pub fn to_record(&self) -> [u8; RECORD_LEN] {
        let [b0, b1, b2, b3] = self.bind_id.to_le_bytes();
        let [t0, t1] = self.input_timeout_ms.to_le_bytes();
        [
            RECORD_VERSION,
            self.role as u8,
            self.rate as u8,
            self.input as u8,
            self.output as u8,
            self.band as u8,
            self.tx_power,
            self.failsafe as u8,
            b0,
            b1,
            b2,
            b3,
            t0,
            t1,
        ]
    }

    /// Parses a record of version 1 or 2; every field is range-checked.
    pub fn from_record(record: &[u8]) -> Result<Self, DecodeError> {
        let Some(&version) = record.first() else {
            return Err(DecodeError::Length { found: 0 });
        };
        let (common, input_timeout_ms) = match version {
            1 => (
                <[u8; RECORD_V1_LEN]>::try_from(record).ok(),
                DEFAULT_INPUT_TIMEOUT_MS,
            ),
            RECORD_VERSION => {
                let Some((common, [t0, t1])) = record
                    .split_first_chunk::<RECORD_V1_LEN>()
                    .and_then(|(common, rest)| Some((*common, <[u8; 2]>::try_from(rest).ok()?)))
                else {
                    return Err(DecodeError::Length {
                        found: record.len(),
                    });
                };
                let timeout = u16::from_le_bytes([t0, t1]);
                if !INPUT_TIMEOUT_MS.contains(&timeout) {
                    return Err(DecodeError::Field {
                        offset: RECORD_V1_LEN,
                    });
                }
                (Some(common), timeout)
            }
            found => return Err(DecodeError::Version { found }),
        };
        let Some(
            [
                _,
                role,
                rate,
                input,
                output,
                band,
                tx_power,
                failsafe,
                b0,
                b1,
                b2,
                b3,
            ],
        ) = common
        else {
            return Err(DecodeError::Length {
                found: record.len(),
            });
        };
        let field = |offset: usize| DecodeError::Field { offset };
        Ok(Self {
            role: match role {
                0 => Role::Transmitter,
                1 => Role::Receiver,
                _ => return Err(field(1)),
            },
            rate: match rate {
                0 => RateMode::Bps4800,
                1 => RateMode::Bps9600,
                2 => RateMode::Bps19200,
                3 => RateMode::Bps57600,
                4 => RateMode::Bps125000,
                _ => return Err(field(2)),
            },
            input: match input {
                0 => InputProtocol::Ppm,
                1 => InputProtocol::Crsf,
                2 => InputProtocol::Crsf115200,
                _ => return Err(field(3)),
            },
            output: match output {
                0 => OutputProtocol::Off,
                1 => OutputProtocol::Crsf,
                2 => OutputProtocol::SPort,
                3 => OutputProtocol::FrskyHub,
                _ => return Err(field(4)),
            },
            band: match band {
                0 => Band::Mhz433,
                1 => Band::Mhz868,
                2 => Band::Mhz915,
                _ => return Err(field(5)),
            },
            tx_power: if tx_power <= 7 {
                tx_power
            } else {
                return Err(field(6));
            },
            failsafe: match failsafe {
                0 => FailsafeOutput::HoldLast,
                1 => FailsafeOutput::StopPulses,
                _ => return Err(field(7)),
            },
            bind_id: u32::from_le_bytes([b0, b1, b2, b3]),
            input_timeout_ms,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_round_trip_and_layout() {
        let settings = Settings {
            role: Role::Receiver,
            rate: RateMode::Bps57600,
            input: InputProtocol::Crsf,
            output: OutputProtocol::FrskyHub,
            band: Band::Mhz915,
            tx_power: 5,
            failsafe: FailsafeOutput::StopPulses,
            bind_id: 0xDEAD_BEEF,
            input_timeout_ms: 750,
        };
        let record = settings.to_record();
        assert_eq!(
            record,
            [2, 1, 3, 1, 3, 2, 5, 1, 0xEF, 0xBE, 0xAD, 0xDE, 0xEE, 0x02]
        );
        assert_eq!(Settings::from_record(&record), Ok(settings));
        assert_eq!(
            Settings::from_record(&Settings::default().to_record()),
            Ok(Settings::default())
        );
        // The slower CRSF rate is input code 2 (older records never hold it).
        let slow = Settings {
            input: InputProtocol::Crsf115200,
            ..settings
        };
        assert_eq!(slow.to_record()[3], 2);
        assert_eq!(Settings::from_record(&slow.to_record()), Ok(slow));
    }

    #[test]
    fn bad_records_are_errors() {
        assert_eq!(
            Settings::from_record(&[]),
            Err(DecodeError::Length { found: 0 })
        );
        assert_eq!(
            Settings::from_record(&[3; 14]),
            Err(DecodeError::Version { found: 3 })
        );
        assert_eq!(
            Settings::from_record(&[2; 12]),
            Err(DecodeError::Length { found: 12 })
        );
        assert_eq!(
            Settings::from_record(&[1; 11]),
            Err(DecodeError::Length { found: 11 })
        );
        let mut record = Settings::default().to_record();
        record[6] = 8;
        assert_eq!(
            Settings::from_record(&record),
            Err(DecodeError::Field { offset: 6 })
        );
        record[6] = 7;
        record[2] = 5;
        assert_eq!(
            Settings::from_record(&record),
            Err(DecodeError::Field { offset: 2 })
        );
        record[2] = 2;
        for (timeout, ok) in [(99u16, false), (100, true), (2_000, true), (2_001, false)] {
            record[12..].copy_from_slice(&timeout.to_le_bytes());
            assert_eq!(
                Settings::from_record(&record).map(|s| s.input_timeout_ms),
                if ok {
                    Ok(timeout)
                } else {
                    Err(DecodeError::Field { offset: 12 })
                }
            );
        }
    }

    #[test]
    fn the_factory_failsafe_stops_pulses_and_old_records_keep_their_meaning() {
        assert_eq!(Settings::default().failsafe, FailsafeOutput::StopPulses);
        assert_eq!(Settings::default().input_timeout_ms, 500);
        // Version-1 records as the previous firmware wrote them: hold last (its default) stays
        // hold last, stop pulses stays stop pulses, and the input timeout is the default.
        let v1_hold = [1, 0, 2, 0, 2, 0, 7, 0, 0x78, 0x56, 0x34, 0x12];
        let settings = Settings::from_record(&v1_hold).unwrap();
        assert_eq!(settings.failsafe, FailsafeOutput::HoldLast);
        assert_eq!(settings.bind_id, 0x1234_5678);
        assert_eq!(settings.input_timeout_ms, DEFAULT_INPUT_TIMEOUT_MS);
        let mut v1_stop = v1_hold;
        v1_stop[7] = 1;
        assert_eq!(
            Settings::from_record(&v1_stop).unwrap().failsafe,
            FailsafeOutput::StopPulses
        );
        // Re-saved, they become version 2 with the same values.
        let upgraded = settings.to_record();
        assert_eq!(upgraded[0], 2);
        assert_eq!(Settings::from_record(&upgraded), Ok(settings));
    }

    proptest::proptest! {
        #[test]
        fn any_bytes_decode_or_error(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..20)) {
            if let Ok(settings) = Settings::from_record(&bytes) {
                // A current record re-encodes to itself; a version-1 record to its upgrade.
                let record = settings.to_record();
                if bytes.first() == Some(&RECORD_VERSION) {
                    proptest::prop_assert_eq!(&record[..], &bytes[..]);
                } else {
                    proptest::prop_assert_eq!(&record[1..RECORD_V1_LEN], &bytes[1..]);
                }
            }
        }
    }
}
