//! UBX-NAV-PVT (class 0x01, id 0x07, 92-byte payload): the receiver's navigation solution —
//! fix type and flags, position, NED velocity, their accuracies, satellites used and the
//! GPS time of week. Layout from the u-blox M8/M9/M10 interface descriptions (identical
//! across the three for the fields read here).

/// NAV class.
pub const CLASS: u8 = 0x01;
/// NAV-PVT id.
pub const ID: u8 = 0x07;
/// NAV-PVT payload length.
pub const LEN: usize = 92;

/// `fixType` of NAV-PVT.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FixType {
    /// No fix.
    NoFix,
    /// Dead reckoning only.
    DeadReckoning,
    /// 2-D fix (no usable height).
    Fix2D,
    /// 3-D fix.
    Fix3D,
    /// GNSS combined with dead reckoning.
    GnssDeadReckoning,
    /// Time only.
    TimeOnly,
    /// A value the documents do not define.
    Unknown(u8),
}

impl From<u8> for FixType {
    fn from(v: u8) -> Self {
        match v {
            0 => Self::NoFix,
            1 => Self::DeadReckoning,
            2 => Self::Fix2D,
            3 => Self::Fix3D,
            4 => Self::GnssDeadReckoning,
            5 => Self::TimeOnly,
            other => Self::Unknown(other),
        }
    }
}

/// The NAV-PVT fields the flight controller uses, in the receiver's integer units.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NavPvt {
    /// GPS time of week of the navigation epoch (ms).
    pub itow_ms: u32,
    /// Fix type.
    pub fix_type: FixType,
    /// `flags` (bit 0 gnssFixOK, bit 1 diffSoln, bits 6–7 carrSoln).
    pub flags: u8,
    /// Satellites used in the solution.
    pub num_sv: u8,
    /// Longitude (deg·1e-7).
    pub lon_e7: i32,
    /// Latitude (deg·1e-7).
    pub lat_e7: i32,
    /// Height above the ellipsoid (mm).
    pub height_mm: i32,
    /// Height above mean sea level (mm).
    pub h_msl_mm: i32,
    /// Horizontal accuracy estimate (mm).
    pub h_acc_mm: u32,
    /// Vertical accuracy estimate (mm).
    pub v_acc_mm: u32,
    /// Velocity north, east, down (mm/s).
    pub vel_ned_mmps: [i32; 3],
    /// Ground speed (mm/s).
    pub g_speed_mmps: i32,
    /// Heading of motion (deg·1e-5).
    pub head_mot_e5: i32,
    /// Speed accuracy estimate (mm/s).
    pub s_acc_mmps: u32,
    /// Position dilution of precision (·0.01).
    pub p_dop_e2: u16,
}

/// Why a NAV-PVT payload was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// The payload is not 92 bytes long.
    Length,
}

fn u32_at(p: &[u8], at: usize) -> Option<u32> {
    let b = p.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes(b.try_into().ok()?))
}

fn i32_at(p: &[u8], at: usize) -> Option<i32> {
    u32_at(p, at).map(|v| i32::from_le_bytes(v.to_le_bytes()))
}

fn u16_at(p: &[u8], at: usize) -> Option<u16> {
    let b = p.get(at..at.checked_add(2)?)?;
    Some(u16::from_le_bytes(b.try_into().ok()?))
}

impl NavPvt {
    /// `flags` bit 0: the fix is valid within the receiver's DOP and accuracy masks.
    pub const FLAG_GNSS_FIX_OK: u8 = 0x01;

    /// Decodes a NAV-PVT payload (the frame's checksum already verified).
    ///
    /// # Errors
    /// [`DecodeError::Length`] unless the payload is exactly [`LEN`] bytes.
    pub fn decode(p: &[u8]) -> Result<Self, DecodeError> {
        if p.len() != LEN {
            return Err(DecodeError::Length);
        }
        Self::fields(p).ok_or(DecodeError::Length)
    }

    fn fields(p: &[u8]) -> Option<Self> {
        Some(Self {
            itow_ms: u32_at(p, 0)?,
            fix_type: FixType::from(*p.get(20)?),
            flags: *p.get(21)?,
            num_sv: *p.get(23)?,
            lon_e7: i32_at(p, 24)?,
            lat_e7: i32_at(p, 28)?,
            height_mm: i32_at(p, 32)?,
            h_msl_mm: i32_at(p, 36)?,
            h_acc_mm: u32_at(p, 40)?,
            v_acc_mm: u32_at(p, 44)?,
            vel_ned_mmps: [i32_at(p, 48)?, i32_at(p, 52)?, i32_at(p, 56)?],
            g_speed_mmps: i32_at(p, 60)?,
            head_mot_e5: i32_at(p, 64)?,
            s_acc_mmps: u32_at(p, 68)?,
            p_dop_e2: u16_at(p, 76)?,
        })
    }

    /// The payload a receiver would send for these fields (the fields not read here are
    /// zero): what the simulator's receiver writes, so the firmware path is exercised byte
    /// for byte. `decode(&p.encode())` gives `p` back.
    #[must_use]
    pub fn encode(&self) -> [u8; LEN] {
        let mut p = [0u8; LEN];
        let fix = match self.fix_type {
            FixType::NoFix => 0,
            FixType::DeadReckoning => 1,
            FixType::Fix2D => 2,
            FixType::Fix3D => 3,
            FixType::GnssDeadReckoning => 4,
            FixType::TimeOnly => 5,
            FixType::Unknown(v) => v,
        };
        let [v0, v1, v2] = self.vel_ned_mmps;
        let fields: [(usize, &[u8]); 17] = [
            (0, &self.itow_ms.to_le_bytes()),
            (20, &[fix]),
            (21, &[self.flags]),
            (23, &[self.num_sv]),
            (24, &self.lon_e7.to_le_bytes()),
            (28, &self.lat_e7.to_le_bytes()),
            (32, &self.height_mm.to_le_bytes()),
            (36, &self.h_msl_mm.to_le_bytes()),
            (40, &self.h_acc_mm.to_le_bytes()),
            (44, &self.v_acc_mm.to_le_bytes()),
            (48, &v0.to_le_bytes()),
            (52, &v1.to_le_bytes()),
            (56, &v2.to_le_bytes()),
            (60, &self.g_speed_mmps.to_le_bytes()),
            (64, &self.head_mot_e5.to_le_bytes()),
            (68, &self.s_acc_mmps.to_le_bytes()),
            (76, &self.p_dop_e2.to_le_bytes()),
        ];
        for (at, bytes) in fields {
            for (dst, &src) in p.iter_mut().skip(at).zip(bytes) {
                *dst = src;
            }
        }
        p
    }

    /// True for a 3-D fix (or GNSS + dead reckoning) the receiver itself calls valid
    /// (`gnssFixOK`): the only kind the INS may use for position.
    #[must_use]
    pub fn has_3d_fix(&self) -> bool {
        matches!(self.fix_type, FixType::Fix3D | FixType::GnssDeadReckoning)
            && self.flags & Self::FLAG_GNSS_FIX_OK != 0
    }
}
