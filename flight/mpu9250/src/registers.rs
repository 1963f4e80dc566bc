//! MPU-9250 and AK8963 register map (InvenSense RM-MPU-9250A-00 rev 1.6, sections 4 and 5).

/// SMPLRT_DIV (0x19): sample rate = internal rate / (1 + value).
pub const SMPLRT_DIV: u8 = 0x19;
/// CONFIG (0x1A): DLPF_CFG in bits 2:0.
pub const CONFIG: u8 = 0x1A;
/// GYRO_CONFIG (0x1B): GYRO_FS_SEL in bits 4:3, FCHOICE_B 1:0 = 0.
pub const GYRO_CONFIG: u8 = 0x1B;
/// ACCEL_CONFIG (0x1C): ACCEL_FS_SEL in bits 4:3.
pub const ACCEL_CONFIG: u8 = 0x1C;
/// ACCEL_CONFIG2 (0x1D): A_DLPFCFG in bits 2:0, ACCEL_FCHOICE_B (bit 3) = 0.
pub const ACCEL_CONFIG2: u8 = 0x1D;
/// I2C_MST_CTRL (0x24): I2C_MST_CLK in bits 3:0 (13 = 400 kHz).
pub const I2C_MST_CTRL: u8 = 0x24;
/// I2C_SLV0_ADDR (0x25): bit 7 = read.
pub const I2C_SLV0_ADDR: u8 = 0x25;
/// I2C_SLV0_REG (0x26).
pub const I2C_SLV0_REG: u8 = 0x26;
/// I2C_SLV0_CTRL (0x27): bit 7 enable, bits 3:0 length.
pub const I2C_SLV0_CTRL: u8 = 0x27;
/// INT_PIN_CFG (0x37).
pub const INT_PIN_CFG: u8 = 0x37;
/// INT_ENABLE (0x38): RAW_RDY_EN = bit 0.
pub const INT_ENABLE: u8 = 0x38;
/// INT_STATUS (0x3A): RAW_DATA_RDY_INT = bit 0.
pub const INT_STATUS: u8 = 0x3A;
/// ACCEL_XOUT_H (0x3B): accel (6), temperature (2), gyro (6), then EXT_SENS_DATA_00 (0x49).
pub const ACCEL_XOUT_H: u8 = 0x3B;
/// EXT_SENS_DATA_00 (0x49): bytes read by the I²C master.
pub const EXT_SENS_DATA_00: u8 = 0x49;
/// I2C_SLV0_DO (0x63): byte written by slave 0.
pub const I2C_SLV0_DO: u8 = 0x63;
/// USER_CTRL (0x6A).
pub const USER_CTRL: u8 = 0x6A;
/// PWR_MGMT_1 (0x6B).
pub const PWR_MGMT_1: u8 = 0x6B;
/// PWR_MGMT_2 (0x6C): 0 enables every axis.
pub const PWR_MGMT_2: u8 = 0x6C;
/// WHO_AM_I (0x75).
pub const WHO_AM_I: u8 = 0x75;

/// SPI read flag (RM §"SPI interface": the MSB of the address selects read).
pub const READ: u8 = 0x80;
/// PWR_MGMT_1.H_RESET.
pub const H_RESET: u8 = 0x80;
/// PWR_MGMT_1.CLKSEL = 1: best available clock (gyro PLL).
pub const CLKSEL_PLL: u8 = 0x01;
/// USER_CTRL.I2C_MST_EN.
pub const I2C_MST_EN: u8 = 0x20;
/// USER_CTRL.I2C_IF_DIS: SPI only.
pub const I2C_IF_DIS: u8 = 0x10;
/// INT_PIN_CFG: LATCH_INT_EN | INT_ANYRD_2CLEAR — INT high until any register read.
pub const INT_LATCHED_ANY_READ_CLEARS: u8 = 0x30;
/// INT_ENABLE.RAW_RDY_EN.
pub const RAW_RDY_EN: u8 = 0x01;
/// I2C_MST_CLK = 13: 400 kHz.
pub const I2C_MST_400KHZ: u8 = 0x0D;
/// I2C_SLVx_CTRL.I2C_SLVx_EN.
pub const SLV_EN: u8 = 0x80;

/// Identities WHO_AM_I may report: MPU-9250 and MPU-9255.
pub const WHO_AM_I_VALUES: [u8; 2] = [0x71, 0x73];

/// AK8963 (AK8963C datasheet §8).
pub mod ak8963 {
    /// 7-bit I²C address.
    pub const ADDRESS: u8 = 0x0C;
    /// WIA: device ID.
    pub const WIA: u8 = 0x00;
    /// Expected WIA value.
    pub const WIA_VALUE: u8 = 0x48;
    /// ST1: DRDY = bit 0.
    pub const ST1: u8 = 0x02;
    /// CNTL1: MODE bits 3:0, BIT (16-bit output) = bit 4.
    pub const CNTL1: u8 = 0x0A;
    /// CNTL2: SRST = bit 0.
    pub const CNTL2: u8 = 0x0B;
    /// ASAX..ASAZ: sensitivity adjustment (fuse ROM).
    pub const ASAX: u8 = 0x10;
    /// CNTL1 power-down.
    pub const MODE_POWER_DOWN: u8 = 0x00;
    /// CNTL1 fuse-ROM access.
    pub const MODE_FUSE_ROM: u8 = 0x0F;
    /// CNTL1 16-bit output, continuous measurement mode 2 (100 Hz).
    pub const MODE_CONTINUOUS_100HZ_16BIT: u8 = 0x16;
    /// CNTL2 soft reset.
    pub const SRST: u8 = 0x01;
    /// ST2.HOFL: magnetic sensor overflow.
    pub const ST2_HOFL: u8 = 0x08;
    /// 16-bit sensitivity: 0.15 µT/LSB.
    pub const MICROTESLA_PER_LSB: f32 = 0.15;
}
