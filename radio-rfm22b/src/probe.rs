//! Identification: is there an Si4432 on the bus, and which silicon revision (0x00/0x01).
//! Shared by [`Rfm22b::probe`](crate::Rfm22b::probe) and radio layers that run their own
//! register scripts over [`Bus`](crate::Bus) (the `openlrs-ng` crate), so all of them report
//! an absent chip the same way.

use crate::Error;
use crate::registers::DEVICE_TYPE_SI443X;

/// Silicon revision from register 0x01 (datasheet register 01h, "Device Version").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Version {
    /// 0x02: rev V2.
    V2,
    /// 0x04: rev A0.
    A0,
    /// 0x06: rev B1 (what RFM22B modules carry).
    B1,
    /// A value the datasheet does not list.
    Unknown(u8),
}

impl From<u8> for Version {
    fn from(v: u8) -> Self {
        match v {
            0x02 => Version::V2,
            0x04 => Version::A0,
            0x06 => Version::B1,
            other => Version::Unknown(other),
        }
    }
}

/// What a probe found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChipInfo {
    /// Silicon revision.
    pub version: Version,
}

/// The device-type check on what 0x00/0x01 read (`[device type, version]`, one burst). A
/// bus with no chip on it reads all 0x00 or all 0xFF, so it fails here instead of passing
/// unnoticed. Synchronous on purpose: an
/// extra nested future in `Rfm22b::probe` cost its `init` 65 instructions on the M4.
pub fn check_identity<E>([device_type, version]: [u8; 2]) -> Result<ChipInfo, Error<E>> {
    if device_type & 0x1F != DEVICE_TYPE_SI443X {
        return Err(Error::NotAnSi4432 {
            device_type,
            version,
        });
    }
    Ok(ChipInfo {
        version: Version::from(version & 0x1F),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions() {
        assert_eq!(Version::from(0x02), Version::V2);
        assert_eq!(Version::from(0x04), Version::A0);
        assert_eq!(Version::from(0x06), Version::B1);
        assert_eq!(Version::from(0x07), Version::Unknown(7));
    }
}
