//! MPU-9250 configuration values and their scale factors (RM-MPU-9250A-00 §4.5–4.8).

/// Gyro full scale (GYRO_FS_SEL).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GyroRange {
    /// ±250 °/s.
    Dps250 = 0,
    /// ±500 °/s.
    Dps500 = 1,
    /// ±1000 °/s.
    Dps1000 = 2,
    /// ±2000 °/s.
    Dps2000 = 3,
}

impl GyroRange {
    /// Full scale in °/s.
    #[must_use]
    pub const fn full_scale_dps(self) -> f32 {
        match self {
            Self::Dps250 => 250.0,
            Self::Dps500 => 500.0,
            Self::Dps1000 => 1000.0,
            Self::Dps2000 => 2000.0,
        }
    }

    /// rad/s per LSB.
    #[must_use]
    pub fn radps_per_lsb(self) -> f32 {
        self.full_scale_dps() / 32768.0 * (core::f32::consts::PI / 180.0)
    }
}

/// Accelerometer full scale (ACCEL_FS_SEL).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AccelRange {
    /// ±2 g.
    G2 = 0,
    /// ±4 g.
    G4 = 1,
    /// ±8 g.
    G8 = 2,
    /// ±16 g.
    G16 = 3,
}

impl AccelRange {
    /// m/s² per LSB (g = 9.80665 m/s²).
    #[must_use]
    pub fn mps2_per_lsb(self) -> f32 {
        let g = match self {
            Self::G2 => 2.0,
            Self::G4 => 4.0,
            Self::G8 => 8.0,
            Self::G16 => 16.0,
        };
        g * 9.806_65 / 32768.0
    }
}

/// Digital low-pass filter of gyro (DLPF_CFG) and accelerometer (A_DLPFCFG). All of these
/// run the internal sample clock at 1 kHz, which SMPLRT_DIV divides.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Dlpf {
    /// Gyro 184 Hz / accel 184 Hz (the Tau Labs default).
    Hz184 = 1,
    /// 92 Hz.
    Hz92 = 2,
    /// 41 Hz.
    Hz41 = 3,
    /// 20 Hz.
    Hz20 = 4,
    /// 10 Hz.
    Hz10 = 5,
    /// 5 Hz.
    Hz5 = 6,
}

/// Output data rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SampleRate {
    /// 500 Hz (SMPLRT_DIV = 1).
    Hz500,
    /// 1 kHz (SMPLRT_DIV = 0).
    Hz1000,
}

impl SampleRate {
    /// SMPLRT_DIV for the 1 kHz internal rate.
    #[must_use]
    pub const fn divider(self) -> u8 {
        match self {
            Self::Hz500 => 1,
            Self::Hz1000 => 0,
        }
    }

    /// Rate in Hz.
    #[must_use]
    pub const fn frequency_hz(self) -> u32 {
        match self {
            Self::Hz500 => 500,
            Self::Hz1000 => 1000,
        }
    }
}

/// Driver configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Gyro range.
    pub gyro_range: GyroRange,
    /// Accelerometer range.
    pub accel_range: AccelRange,
    /// Low-pass filter.
    pub dlpf: Dlpf,
    /// Output data rate.
    pub sample_rate: SampleRate,
    /// Whether to bring up the AK8963 and read it with every sample.
    pub magnetometer: bool,
}

impl Default for Config {
    /// The flight default (Tau Labs' Sparky2 defaults, `flight/targets/sparky2/` and
    /// `shared/uavobjectdefinition/hwsparky2.xml`): 500 Hz, 184 Hz DLPF, ±2000 °/s, ±8 g,
    /// magnetometer on.
    fn default() -> Self {
        Self {
            gyro_range: GyroRange::Dps2000,
            accel_range: AccelRange::G8,
            dlpf: Dlpf::Hz184,
            sample_rate: SampleRate::Hz500,
            magnetometer: true,
        }
    }
}
