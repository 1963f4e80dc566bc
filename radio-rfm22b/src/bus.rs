//! Register access framing over an async `SpiDevice`: the address byte carries the
//! direction in bit 7 (1 = write), and bursts auto-increment (datasheet, "Serial Peripheral Interface").

use embedded_hal_async::spi::{Operation, SpiDevice};

use crate::Error;

const WRITE: u8 = 0x80;

/// The chip's SPI interface. The only place that talks to the `SpiDevice`.
///
/// Cancel-safety of every method: each is one `SpiDevice::transaction`, so dropping it is
/// exactly as safe as dropping the device's transaction future. If that future does not
/// release chip select when dropped, nSEL can stay low and the chip would read the next
/// transaction as the continuation of the cut one.
pub struct Bus<SPI> {
    spi: SPI,
}

impl<SPI> Bus<SPI> {
    /// Wraps an SPI device (mode 0, ≤ 10 MHz, chip select handled by the device).
    pub fn new(spi: SPI) -> Self {
        Self { spi }
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }
}

impl<SPI: SpiDevice> Bus<SPI> {
    /// Reads one register.
    pub async fn read(&mut self, address: u8) -> Result<u8, Error<SPI::Error>> {
        let mut value = [0u8; 1];
        self.read_burst(address, &mut value).await?;
        let [v] = value;
        Ok(v)
    }

    /// Writes one register.
    pub async fn write(&mut self, address: u8, value: u8) -> Result<(), Error<SPI::Error>> {
        self.write_burst(address, &[value]).await
    }

    /// Reads consecutive registers (or the FIFO, which does not increment) in one transaction.
    pub async fn read_burst(
        &mut self,
        address: u8,
        buf: &mut [u8],
    ) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[address & !WRITE]), Operation::Read(buf)])
            .await
            .map_err(Error::Bus)
    }

    /// Writes consecutive registers (or the FIFO) in one transaction.
    pub async fn write_burst(&mut self, address: u8, data: &[u8]) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[address | WRITE]), Operation::Write(data)])
            .await
            .map_err(Error::Bus)
    }
}
