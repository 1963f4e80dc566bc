//! Identification: device type and silicon revision (registers 0x00/0x01), and the
//! software reset with its chip-ready wait.

use embedded_hal::delay::DelayNs;
use embedded_hal_async::spi::SpiDevice;

use crate::registers::*;
use crate::{Bus, Error};

/// Silicon revision from register 0x01 (datasheet §9, "Device Version").
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

/// What [`probe`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChipInfo {
    /// Silicon revision.
    pub version: Version,
}

/// Reads the identification registers. An absent chip reads 0x00 or 0xFF and is reported as
/// [`Error::NotAnSi4432`], never a hang.
pub async fn probe<SPI: SpiDevice>(bus: &mut Bus<SPI>) -> Result<ChipInfo, Error<SPI::Error>> {
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

/// Software reset (0x07 bit 7), then polls interrupt status 2 for "chip ready" for up to
/// `timeout_ms`. Reading status 1 and 2 also releases nIRQ.
pub async fn software_reset<SPI: SpiDevice, D: DelayNs>(
    bus: &mut Bus<SPI>,
    delay: &mut D,
    timeout_ms: u32,
) -> Result<(), Error<SPI::Error>> {
    bus.write(OPERATING_MODE_1, OPERATING_MODE_1_SWRESET)
        .await?;
    for _ in 0..timeout_ms {
        delay.delay_ms(1);
        let mut status = [0u8; 2];
        bus.read_burst(INTERRUPT_STATUS_1, &mut status).await?;
        let [_, status2] = status;
        if status2 & INTERRUPT_STATUS_2_CHIPRDY != 0 {
            return Ok(());
        }
    }
    Err(Error::Timeout)
}

#[cfg(test)]
mod tests {
    use super::*;
    use embassy_futures::block_on;
    use embedded_hal_mock::eh1::spi::{Mock, Transaction};

    fn id_read(device_type: u8, version: u8) -> Vec<Transaction<u8>> {
        vec![
            Transaction::transaction_start(),
            Transaction::write(0x00),
            Transaction::read_vec(vec![device_type, version]),
            Transaction::transaction_end(),
        ]
    }

    #[test]
    fn probe_reports_b1() {
        let spi = Mock::new(&id_read(0x08, 0x06));
        let mut bus = Bus::new(spi);
        let info = block_on(probe(&mut bus)).unwrap();
        assert_eq!(info.version, Version::B1);
        bus.release().done();
    }

    #[test]
    fn probe_rejects_unplugged_chip() {
        for floating in [0x00, 0xFF] {
            let spi = Mock::new(&id_read(floating, floating));
            let mut bus = Bus::new(spi);
            let err = block_on(probe(&mut bus)).unwrap_err();
            assert_eq!(
                err,
                Error::NotAnSi4432 {
                    device_type: floating,
                    version: floating
                }
            );
            bus.release().done();
        }
    }
}
