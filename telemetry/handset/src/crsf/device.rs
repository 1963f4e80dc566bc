//! Extended-header frames between radio and module: DEVICE_PING 0x28, DEVICE_INFO 0x29, the
//! RADIO_ID 0x3A timing correction and the model-select command 0x32 (CRSF spec).

use crc::{Algorithm, Crc};
use heapless::{String, Vec};

use super::frame::{Error, MAX_PAYLOAD_LEN, be_bytes, frame_type};

/// Sub-type of RADIO_ID carrying the timing correction ("OpenTX sync").
pub const TIMING_SUB_TYPE: u8 = 0x10;
/// Command 0x32 realm of CRSF commands.
pub const COMMAND_CRSF: u8 = 0x10;
/// CRSF command: model select.
pub const COMMAND_MODEL_SELECT: u8 = 0x05;
/// CRSF command: bind (EdgeTX's "Bind" button on a CRSF module).
pub const COMMAND_BIND: u8 = 0x01;
/// Longest device name this module keeps.
pub const DEVICE_NAME_MAX_LEN: usize = 32;

/// CRC-8 poly 0xBA (init 0, unreflected) that command frames carry before the frame CRC.
/// Check value over "123456789" is 0x20.
pub const COMMAND_CRC: Crc<u8> = Crc::<u8>::new(&Algorithm {
    width: 8,
    poly: 0xBA,
    init: 0x00,
    refin: false,
    refout: false,
    xorout: 0x00,
    check: 0x20,
    residue: 0x00,
});

/// Splits off `destination, origin`.
fn split_addresses(frame_type: u8, payload: &[u8]) -> Result<(u8, u8, &[u8]), Error> {
    match payload {
        [destination, origin, rest @ ..] => Ok((*destination, *origin, rest)),
        _ => Err(Error::PayloadLength {
            frame_type,
            length: payload.len(),
        }),
    }
}

/// The inner CRC of a CRSF command (poly 0xBA over the frame type, the addresses, the
/// command set, the sub-command `sub` and its `body`).
fn command_crc(destination: u8, origin: u8, sub: u8, body: &[u8]) -> u8 {
    let mut digest = COMMAND_CRC.digest();
    digest.update(&[frame_type::COMMAND, destination, origin, COMMAND_CRSF, sub]);
    digest.update(body);
    digest.finalize()
}

/// Reads a CRSF command payload (frame type 0x32, command set 0x10) of sub-command `sub`
/// with an `N`-byte body: the addresses and the body, once the inner CRC checks. Another
/// command, or this one with another length, is `Unsupported`.
fn command_from_payload<const N: usize>(
    payload: &[u8],
    sub: u8,
) -> Result<(u8, u8, [u8; N]), Error> {
    let (destination, origin, rest) = split_addresses(frame_type::COMMAND, payload)?;
    match rest {
        [COMMAND_CRSF, s, tail @ ..] if *s == sub => {
            let Some((inner_crc, body)) = tail.split_last() else {
                return Err(Error::Unsupported { sub_type: sub });
            };
            let Ok(body) = <[u8; N]>::try_from(body) else {
                return Err(Error::Unsupported { sub_type: sub });
            };
            if command_crc(destination, origin, sub, &body) == *inner_crc {
                Ok((destination, origin, body))
            } else {
                Err(Error::InnerCrc)
            }
        }
        [COMMAND_CRSF, sub_type, ..] | [sub_type, ..] => Err(Error::Unsupported {
            sub_type: *sub_type,
        }),
        [] => Err(Error::PayloadLength {
            frame_type: frame_type::COMMAND,
            length: payload.len(),
        }),
    }
}

/// DEVICE_PING (0x28): "who is there". EdgeTX ≥ 2.11 sends `C8 04 28 00 EA 54`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DevicePing {
    /// Addressee (0x00 = everyone).
    pub destination: u8,
    /// Sender.
    pub origin: u8,
}

impl DevicePing {
    /// The 2-byte payload.
    pub fn to_payload(&self) -> [u8; 2] {
        [self.destination, self.origin]
    }

    /// Reads the payload (bytes after the addresses are ignored).
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        let (destination, origin, _) = split_addresses(frame_type::DEVICE_PING, payload)?;
        Ok(Self {
            destination,
            origin,
        })
    }
}

/// DEVICE_INFO (0x29): name, serial, hardware and firmware ids, parameter count.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeviceInfo {
    /// Addressee.
    pub destination: u8,
    /// Sender (EdgeTX requires 0xEE from a module).
    pub origin: u8,
    /// Device name (no NUL inside).
    pub name: String<DEVICE_NAME_MAX_LEN>,
    /// Four serial bytes. EdgeTX enables ExpressLRS-only features when they read "ELRS".
    pub serial: [u8; 4],
    /// Hardware id.
    pub hardware_id: u32,
    /// Firmware id; EdgeTX reads major/minor/revision from its low three bytes.
    pub firmware_id: u32,
    /// Number of parameters offered.
    pub parameter_count: u8,
    /// Parameter protocol version.
    pub parameter_protocol_version: u8,
}

impl DeviceInfo {
    /// The payload: addresses, name + NUL, then 14 bytes of ids.
    pub fn to_payload(&self) -> Result<Vec<u8, MAX_PAYLOAD_LEN>, Error> {
        let length = 2 + self.name.len() + 1 + 14;
        let too_long = Error::PayloadTooLong { length };
        if self.name.as_bytes().contains(&0) {
            return Err(Error::BadString);
        }
        let mut payload = Vec::new();
        payload
            .extend_from_slice(&[self.destination, self.origin])
            .map_err(|_| too_long)?;
        payload
            .extend_from_slice(self.name.as_bytes())
            .map_err(|_| too_long)?;
        payload.push(0).map_err(|_| too_long)?;
        payload
            .extend_from_slice(&self.serial)
            .map_err(|_| too_long)?;
        payload
            .extend_from_slice(&self.hardware_id.to_be_bytes())
            .map_err(|_| too_long)?;
        payload
            .extend_from_slice(&self.firmware_id.to_be_bytes())
            .map_err(|_| too_long)?;
        payload
            .extend_from_slice(&[self.parameter_count, self.parameter_protocol_version])
            .map_err(|_| too_long)?;
        Ok(payload)
    }

    /// Reads the payload.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        let (destination, origin, rest) = split_addresses(frame_type::DEVICE_INFO, payload)?;
        let end = rest
            .iter()
            .position(|&b| b == 0)
            .ok_or(Error::Unterminated)?;
        let (name, ids) = rest.split_at_checked(end).ok_or(Error::Unterminated)?;
        let name = core::str::from_utf8(name).map_err(|_| Error::BadString)?;
        let name = String::try_from(name).map_err(|_| Error::BadString)?;
        // `ids` starts with the NUL.
        let wrong_length = Error::PayloadLength {
            frame_type: frame_type::DEVICE_INFO,
            length: payload.len(),
        };
        let [
            _,
            s0,
            s1,
            s2,
            s3,
            h0,
            h1,
            h2,
            h3,
            f0,
            f1,
            f2,
            f3,
            count,
            version,
        ]: [u8; 15] = ids.try_into().map_err(|_| wrong_length)?;
        Ok(Self {
            destination,
            origin,
            name,
            serial: [s0, s1, s2, s3],
            hardware_id: u32::from_be_bytes([h0, h1, h2, h3]),
            firmware_id: u32::from_be_bytes([f0, f1, f2, f3]),
            parameter_count: count,
            parameter_protocol_version: version,
        })
    }
}

/// RADIO_ID (0x3A) sub-type 0x10: the module tells the radio at which period and phase to
/// send its channel frames (EdgeTX mixer sync).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TimingCorrection {
    /// Addressee (EdgeTX requires 0xEA).
    pub destination: u8,
    /// Sender (0xEE).
    pub origin: u8,
    /// Frame period the radio should use, 0.1 µs (EdgeTX clamps to 850 … 50 000 µs).
    pub interval_100ns: u32,
    /// Phase correction, 0.1 µs; positive = the radio's frame arrived early.
    pub offset_100ns: i32,
}

impl TimingCorrection {
    /// The 11-byte payload.
    pub fn to_payload(&self) -> [u8; 11] {
        let [i0, i1, i2, i3] = self.interval_100ns.to_be_bytes();
        let [o0, o1, o2, o3] = self.offset_100ns.to_be_bytes();
        [
            self.destination,
            self.origin,
            TIMING_SUB_TYPE,
            i0,
            i1,
            i2,
            i3,
            o0,
            o1,
            o2,
            o3,
        ]
    }

    /// Reads the payload; other RADIO_ID sub-types are `Unsupported`.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        let (destination, origin, rest) = split_addresses(frame_type::RADIO_ID, payload)?;
        let (&sub_type, fields) = rest.split_first().ok_or(Error::PayloadLength {
            frame_type: frame_type::RADIO_ID,
            length: payload.len(),
        })?;
        if sub_type != TIMING_SUB_TYPE {
            return Err(Error::Unsupported { sub_type });
        }
        let wrong_length = Error::PayloadLength {
            frame_type: frame_type::RADIO_ID,
            length: payload.len(),
        };
        if fields.len() != 8 {
            return Err(wrong_length);
        }
        Ok(Self {
            destination,
            origin,
            interval_100ns: u32::from_be_bytes(be_bytes(fields, 0).ok_or(wrong_length)?),
            offset_100ns: i32::from_be_bytes(be_bytes(fields, 4).ok_or(wrong_length)?),
        })
    }
}

/// Command 0x32 / CRSF 0x10 / model select 0x05: the radio tells the module which model is
/// active (first frame after init). Carries an inner CRC (poly 0xBA) over type..model id.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModelSelect {
    /// Addressee (0xEE).
    pub destination: u8,
    /// Sender (0xEA).
    pub origin: u8,
    /// Model id (receiver number) chosen in the radio.
    pub model_id: u8,
}

impl ModelSelect {
    fn inner_crc(&self) -> u8 {
        command_crc(
            self.destination,
            self.origin,
            COMMAND_MODEL_SELECT,
            &[self.model_id],
        )
    }

    /// The 6-byte payload, inner CRC last.
    pub fn to_payload(&self) -> [u8; 6] {
        [
            self.destination,
            self.origin,
            COMMAND_CRSF,
            COMMAND_MODEL_SELECT,
            self.model_id,
            self.inner_crc(),
        ]
    }

    /// Reads the payload; other commands are `Unsupported`.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        let (destination, origin, [model_id]) =
            command_from_payload(payload, COMMAND_MODEL_SELECT)?;
        Ok(Self {
            destination,
            origin,
            model_id,
        })
    }
}

/// Command 0x32 / CRSF 0x10 / bind 0x01: the pilot pressed "Bind" in the radio's model setup
/// (`C8 07 32 EE EA 10 01 <crc 0xBA> <crc>`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BindCommand {
    /// Addressee (0xEE).
    pub destination: u8,
    /// Sender (0xEA).
    pub origin: u8,
}

impl BindCommand {
    fn inner_crc(&self) -> u8 {
        command_crc(self.destination, self.origin, COMMAND_BIND, &[])
    }

    /// The 5-byte payload, inner CRC last.
    pub fn to_payload(&self) -> [u8; 5] {
        [
            self.destination,
            self.origin,
            COMMAND_CRSF,
            COMMAND_BIND,
            self.inner_crc(),
        ]
    }

    /// Reads the payload.
    pub fn from_payload(payload: &[u8]) -> Result<Self, Error> {
        let (destination, origin, []) = command_from_payload(payload, COMMAND_BIND)?;
        Ok(Self {
            destination,
            origin,
        })
    }
}
