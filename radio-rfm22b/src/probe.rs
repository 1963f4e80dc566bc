//! Identification: is there an Si4432 on the bus, and which silicon revision (0x00/0x01).
//! Shared by [`Rfm22b::probe`](crate::Rfm22b::probe) and the OpenLRSng radio layer, so both
//! report an absent chip the same way.

use embedded_hal_async::spi::SpiDevice;

use crate::Error;
use crate::bus::Bus;
use crate::registers::{DEVICE_TYPE, DEVICE_TYPE_SI443X};

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

/// Reads the identification registers (0x00/0x01). A bus with no chip on it reads all
/// 0x00 or all 0xFF, so it fails the device-type check instead of passing unnoticed.
pub(crate) async fn identify<SPI: SpiDevice>(
    bus: &mut Bus<SPI>,
) -> Result<ChipInfo, Error<SPI::Error>> {
    let mut id = [0u8; 2];
    bus.read_burst(DEVICE_TYPE, &mut id).await?;
    let [device_type, version] = id;
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
