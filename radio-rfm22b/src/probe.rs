//! Identification: the silicon revision reported by register 0x01.

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
