//! Run-time control of a configured chip: hop channel, power, headers, carrier, a new
//! configuration without reset, RSSI, temperature, the health check and idle/sleep.

use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;

use crate::carrier::Carrier;
use crate::config::Config;
use crate::measure;
use crate::power::TxPower;
use crate::registers::*;
use crate::{Error, Rfm22b};

/// The ADC conversion takes ~305 µs (datasheet, "Temperature Sensor"); poll every 100 µs, at most 10 times.
const ADC_POLLS: u32 = 10;

impl<SPI, IRQ, SDN, D> Rfm22b<SPI, IRQ, SDN, D>
where
    SPI: SpiDevice,
    IRQ: Wait,
    SDN: OutputPin,
    D: DelayNs,
{
    /// Programs a new configuration without resetting the chip (e.g. OpenLRSng's switch
    /// between the bind and the normal modem profile). Keeps the current hop channel.
    ///
    /// Cancel-safety: dropping it leaves a mix of old and new registers; call it again.
    pub async fn apply(&mut self, config: Config) -> Result<(), Error<SPI::Error>> {
        config.validate()?;
        self.abort_if_busy().await?;
        self.config = Some(config);
        self.configure(&config).await
    }

    /// Moves hop channel 0 to `carrier` (0x75–0x77), e.g. for a beacon or bind frequency.
    ///
    /// Cancel-safety: safe (one burst write).
    pub async fn set_carrier(&mut self, carrier: Carrier) -> Result<(), Error<SPI::Error>> {
        let config = self.config.as_mut().ok_or(Error::NotInitialised)?;
        config.carrier = carrier;
        self.bus
            .write_burst(FREQUENCY_BAND_SELECT, &carrier.registers())
            .await
    }

    /// Replaces the transmitted header (0x3A–0x3D, first on air first); OpenLRSng changes
    /// one byte per hop.
    ///
    /// Cancel-safety: safe (one burst write).
    pub async fn set_tx_header(&mut self, header: [u8; 4]) -> Result<(), Error<SPI::Error>> {
        // Stored like the channel and power, so the re-init after a power-on reset keeps it.
        let config = self.config.as_mut().ok_or(Error::NotInitialised)?;
        config.packet.set_header_bytes(header);
        self.bus.write_burst(TRANSMIT_HEADER_3, &header).await
    }

    /// Replaces the header that received packets are checked against (0x3F–0x42).
    ///
    /// Cancel-safety: safe (one burst write).
    pub async fn set_check_header(&mut self, header: [u8; 4]) -> Result<(), Error<SPI::Error>> {
        let config = self.config.as_mut().ok_or(Error::NotInitialised)?;
        config.packet.set_check_header_bytes(header);
        self.bus.write_burst(CHECK_HEADER_3, &header).await
    }

    /// Time on air of a packet with `payload_len` bytes under the current configuration, in
    /// µs (preamble, sync, header, length byte, payload, CRC), for slot planning.
    pub fn airtime_us(&self, payload_len: u8) -> Option<u32> {
        let config = self.config.as_ref()?;
        Some(config.packet.airtime_us(&config.modem, payload_len))
    }

    /// The raw RSSI byte now (0x26), as OpenLRSng reports it.
    ///
    /// Cancel-safety: safe (a register read).
    pub async fn rssi_raw(&mut self) -> Result<u8, Error<SPI::Error>> {
        self.bus.read(RSSI).await
    }

    /// Selects hop channel `channel` (0x79): carrier + channel × spacing. Takes effect at
    /// once (the PLL settles within the 200 µs the chip waits before TX/RX).
    ///
    /// Cancel-safety: safe (one register write).
    pub async fn set_channel(&mut self, channel: u8) -> Result<(), Error<SPI::Error>> {
        self.bus.write(HOP_CHANNEL, channel).await?;
        self.channel = channel;
        Ok(())
    }

    /// Changes the output power (0x6D).
    ///
    /// Cancel-safety: safe (one register write).
    pub async fn set_tx_power(&mut self, power: TxPower) -> Result<(), Error<SPI::Error>> {
        let config = self.config.as_mut().ok_or(Error::NotInitialised)?;
        config.tx_power = power;
        let value = power.register(config.lna_switch);
        self.bus.write(TX_POWER, value).await
    }

    /// READY: crystal on (≈ 0.8 mA), about 200 µs to TX/RX. Also aborts a TX/RX left running.
    ///
    /// Cancel-safety: safe.
    pub async fn idle(&mut self) -> Result<(), Error<SPI::Error>> {
        self.bus.write(OPERATING_MODE_1, MODE_XTON).await?;
        self.bus
            .write_burst(INTERRUPT_ENABLE_1, &[0x00, 0x00])
            .await?;
        self.busy = false;
        self.clear_status().await
    }

    /// STANDBY: everything off but the register file (~450 nA); the next TX/RX restarts the
    /// crystal (≈ 600 µs longer).
    ///
    /// Cancel-safety: safe.
    pub async fn sleep(&mut self) -> Result<(), Error<SPI::Error>> {
        self.idle().await?;
        self.bus.write(OPERATING_MODE_1, 0x00).await?;
        self.standby = true;
        Ok(())
    }

    /// The RSSI now (0x26), in dBm (see [`measure::rssi_dbm`]). Meaningful in RX.
    ///
    /// Cancel-safety: safe (a register read).
    pub async fn rssi_dbm(&mut self) -> Result<i16, Error<SPI::Error>> {
        let raw = self.bus.read(RSSI).await?;
        let offset = self.config.map_or(0, |c| c.packet.rssi_offset());
        Ok(measure::rssi_dbm(raw, offset))
    }

    /// Measures the chip temperature, in tenths of °C.
    ///
    /// Cancel-safety: safe.
    pub async fn read_temperature_decidegrees_c(&mut self) -> Result<i16, Error<SPI::Error>> {
        self.bus.write(ADC_CONFIG, ADC_START).await?;
        for _ in 0..ADC_POLLS {
            self.delay.delay_us(100).await;
            if self.bus.read(ADC_CONFIG).await? & ADC_START != 0 {
                let adc = self.bus.read(ADC_VALUE).await?;
                if adc == 0xFF {
                    // A bus with nothing on it reads "done" and 0xFF at once: make sure a
                    // chip answered before reporting 63.5 °C.
                    self.probe().await?;
                }
                return Ok(measure::temperature_decidegrees_c(adc));
            }
        }
        Err(Error::Timeout)
    }

    /// Checks that the chip still holds its configuration: the identification and GPIO1
    /// (0x0C, which reads 0 after a silent reset — OpenLRSng's "locked module" test). On a
    /// lost configuration it re-initialises and returns [`Error::ChipReset`].
    ///
    /// Cancel-safety: safe to drop before the re-init starts; during it, as `init`.
    pub async fn check_health(&mut self) -> Result<(), Error<SPI::Error>> {
        let config = self.config.ok_or(Error::NotInitialised)?;
        self.probe().await?;
        let [_, expected, _] = config.gpio.registers();
        if self.bus.read(GPIO1_CONFIG).await? != expected {
            self.reinit().await?;
            return Err(Error::ChipReset);
        }
        Ok(())
    }
}
