//! AK8963 bring-up through the MPU-9250's I²C master (slave 0): soft reset, identity,
//! fuse-ROM sensitivity adjustment (AK8963C datasheet §8.3.11), 16-bit continuous 100 Hz
//! mode, then slave 0 set to fetch ST1..ST2 with every sample.

use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::spi::SpiDevice;

use super::registers::{self as reg, ak8963 as ak};
use super::{Error, Mpu9250};

/// Time for one I²C-master transaction to complete (it runs at the sample rate; 10 ms
/// covers several cycles at 500 Hz) and for AK8963 mode changes (datasheet: 100 µs).
const TRANSFER_DELAY_MS: u32 = 10;

/// Writes one AK8963 register through slave 0.
async fn write<SPI: SpiDevice>(
    dev: &mut Mpu9250<SPI>,
    delay: &mut impl DelayNs,
    register: u8,
    value: u8,
) -> Result<(), Error<SPI::Error>> {
    dev.write(reg::I2C_SLV0_ADDR, ak::ADDRESS).await?;
    dev.write(reg::I2C_SLV0_REG, register).await?;
    dev.write(reg::I2C_SLV0_DO, value).await?;
    dev.write(reg::I2C_SLV0_CTRL, reg::SLV_EN | 1).await?;
    delay.delay_ms(TRANSFER_DELAY_MS).await;
    Ok(())
}

/// Reads `buf.len()` (≤ 15) AK8963 registers through slave 0.
async fn read<SPI: SpiDevice>(
    dev: &mut Mpu9250<SPI>,
    delay: &mut impl DelayNs,
    register: u8,
    buf: &mut [u8],
) -> Result<(), Error<SPI::Error>> {
    let len = u8::try_from(buf.len()).unwrap_or(15).min(15);
    dev.write(reg::I2C_SLV0_ADDR, ak::ADDRESS | reg::READ)
        .await?;
    dev.write(reg::I2C_SLV0_REG, register).await?;
    dev.write(reg::I2C_SLV0_CTRL, reg::SLV_EN | len).await?;
    delay.delay_ms(TRANSFER_DELAY_MS).await;
    dev.read_registers(reg::EXT_SENS_DATA_00, buf).await
}

/// Brings the AK8963 up and returns its per-axis µT/LSB factors.
pub(super) async fn init<SPI: SpiDevice>(
    dev: &mut Mpu9250<SPI>,
    delay: &mut impl DelayNs,
) -> Result<[f32; 3], Error<SPI::Error>> {
    write(dev, delay, ak::CNTL2, ak::SRST).await?;
    let mut wia = [0u8];
    read(dev, delay, ak::WIA, &mut wia).await?;
    if wia[0] != ak::WIA_VALUE {
        return Err(Error::MagnetometerNotFound { wia: wia[0] });
    }
    write(dev, delay, ak::CNTL1, ak::MODE_POWER_DOWN).await?;
    write(dev, delay, ak::CNTL1, ak::MODE_FUSE_ROM).await?;
    let mut asa = [0u8; 3];
    read(dev, delay, ak::ASAX, &mut asa).await?;
    write(dev, delay, ak::CNTL1, ak::MODE_POWER_DOWN).await?;
    write(dev, delay, ak::CNTL1, ak::MODE_CONTINUOUS_100HZ_16BIT).await?;
    // From now on slave 0 reads ST1, HXL..HZH and ST2 (8 bytes) at every sample, landing in
    // EXT_SENS_DATA_00.. right after the gyro bytes of the burst.
    dev.write(reg::I2C_SLV0_ADDR, ak::ADDRESS | reg::READ)
        .await?;
    dev.write(reg::I2C_SLV0_REG, ak::ST1).await?;
    dev.write(reg::I2C_SLV0_CTRL, reg::SLV_EN | 8).await?;
    Ok(asa.map(sensitivity))
}

/// Hadj = H·((ASA − 128)·0.5/128 + 1), times 0.15 µT/LSB (datasheet §8.3.11).
pub(super) fn sensitivity(asa: u8) -> f32 {
    ak::MICROTESLA_PER_LSB * ((f32::from(asa) - 128.0) * 0.5 / 128.0 + 1.0)
}
