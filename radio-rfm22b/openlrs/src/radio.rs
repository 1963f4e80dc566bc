//! The radio layer of the OpenLRSng roles: runs OpenLRSng's own register scripts on an
//! Si4432 through the crate's SPI [`Bus`], and waits for nIRQ against a deadline.
//!
//! It programs registers directly instead of going through a generic modem configuration
//! because air compatibility needs OpenLRSng's exact profiles and the per-hop header XOR
//! (OpenLRSng `common.h`). Interrupt bits: datasheet Table 13/14 (0x03 bit 2 `ipksent`, bit 1
//! `ipkvalid`, bit 0 `icrcerror`); nIRQ stays low until the status registers are read.

use embassy_futures::select::{Either, select};
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;
use heapless::Vec;

use super::bind::BindData;
use super::modem::{self, Purpose, RegOp};
use super::version::BindingVersion;
use crate::RfmType;
use radio_rfm22b::{Bus, ChipInfo};

/// Interrupt status 1: packet sent.
const IPKSENT: u8 = 0x04;
/// Interrupt status 1: valid packet received.
const IPKVALID: u8 = 0x02;
/// Interrupt status 1: CRC error.
const ICRCERROR: u8 = 0x01;
/// Received packet length register.
const REG_RX_LEN: u8 = 0x4B;
/// RSSI register.
const REG_RSSI: u8 = 0x26;
/// AFC correction read-back, bits 9..2 (0x2C holds bits 1..0 in its top two bits).
const REG_AFC: u8 = 0x2B;
/// FIFO access register.
const REG_FIFO: u8 = 0x7F;
/// OpenLRSng gives up on a transmission after 100 ms (`tx_done`).
pub const TX_TIMEOUT_US: u64 = 100_000;
/// Largest packet OpenLRSng exchanges (the 42-byte bind packet).
pub const MAX_PACKET_LEN: usize = 64;

/// A monotonic microsecond clock (e.g. `embassy_time::Instant::now().as_micros()`).
pub trait Clock {
    /// Microseconds since an arbitrary origin.
    fn now_us(&mut self) -> u64;
}

impl<F: FnMut() -> u64> Clock for F {
    fn now_us(&mut self) -> u64 {
        self()
    }
}

/// A packet that passed the header and CRC checks.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Received {
    /// Payload bytes.
    pub bytes: Vec<u8, MAX_PACKET_LEN>,
    /// Raw RSSI (register 0x26) read right after reception.
    pub rssi: u8,
    /// 10-bit AFC correction at the end of the packet (0x2B bits 9..2, 0x2C bits 7..6).
    pub afc: u16,
    /// When the packet was taken from the chip.
    pub at_us: u64,
}

/// Radio-layer failures. `S` is the SPI error, `I` the nIRQ pin error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<S, I> {
    /// Register access failed.
    Radio(radio_rfm22b::Error<S>),
    /// Waiting on nIRQ failed.
    Irq(I),
    /// A register script could not be built (bad modem profile in the bind data).
    Script(modem::Error),
    /// The chip did not report `packet sent` within 100 ms.
    TxTimeout,
}

impl<S: core::fmt::Debug, I: core::fmt::Debug> core::fmt::Display for Error<S, I> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Radio(e) => write!(f, "radio: {e}"),
            Self::Irq(e) => write!(f, "nIRQ pin: {e:?}"),
            Self::Script(e) => write!(f, "register script: {e}"),
            Self::TxTimeout => write!(f, "packet not sent within 100 ms"),
        }
    }
}

impl<S: core::fmt::Debug, I: core::fmt::Debug> core::error::Error for Error<S, I> {}

/// An Si4432 driven the OpenLRSng way.
pub struct Radio<SPI, IRQ, D, C> {
    bus: Bus<SPI>,
    irq: IRQ,
    delay: D,
    clock: C,
    version: BindingVersion,
    band: RfmType,
    diversity: bool,
}

impl<SPI, IRQ, D, C> Radio<SPI, IRQ, D, C>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    /// Wraps the parts; nothing is written until [`Radio::configure`], which first checks
    /// that an Si4432 answers.
    pub fn new(
        spi: SPI,
        irq: IRQ,
        delay: D,
        clock: C,
        version: BindingVersion,
        band: RfmType,
    ) -> Self {
        Self {
            bus: Bus::new(spi),
            irq,
            delay,
            clock,
            version,
            band,
            diversity: false,
        }
    }

    /// Gives the parts back.
    pub fn release(self) -> (SPI, IRQ, D, C) {
        (self.bus.release(), self.irq, self.delay, self.clock)
    }

    /// The generation this radio speaks.
    pub fn version(&self) -> BindingVersion {
        self.version
    }

    /// The module band.
    pub fn band(&self) -> RfmType {
        self.band
    }

    /// Current time from the clock.
    pub fn now_us(&mut self) -> u64 {
        self.clock.now_us()
    }

    /// Runs a register script.
    pub async fn run(&mut self, script: &[RegOp]) -> Result<(), Error<SPI::Error, IRQ::Error>> {
        for op in script {
            match *op {
                RegOp::Write { address, value } => self.bus.write(address, value).await,
                RegOp::Read { address } => self.bus.read(address).await.map(|_| ()),
            }
            .map_err(Error::Radio)?;
        }
        Ok(())
    }

    /// Reads the identification registers (0x00/0x01): an absent, unpowered or mis-wired
    /// module (the bus reads all 0x00 or all 0xFF) gives
    /// `Error::Radio(radio_rfm22b::Error::NotAnSi4432 { .. })`.
    pub async fn probe(&mut self) -> Result<ChipInfo, Error<SPI::Error, IRQ::Error>> {
        let mut id = [0u8; 2];
        self.bus
            .read_burst(radio_rfm22b::registers::DEVICE_TYPE, &mut id)
            .await
            .map_err(Error::Radio)?;
        radio_rfm22b::check_identity(id).map_err(Error::Radio)
    }

    /// `init_rfm`: checks the chip is there ([`Radio::probe`]), then programs the bind or
    /// the link configuration (hop index 0).
    ///
    /// The probe comes first because writes to an absent chip succeed silently: without it
    /// a receiver with no module would listen forever and never report anything.
    pub async fn configure(
        &mut self,
        data: &BindData,
        purpose: Purpose,
    ) -> Result<(), Error<SPI::Error, IRQ::Error>> {
        let script =
            modem::init_script(self.version, self.band, data, purpose).map_err(Error::Script)?;
        self.probe().await?;
        self.diversity = data.diversity();
        self.run(&script).await
    }

    /// `rfmSetChannel`: tunes a hop slot (channel register and the XORed header byte).
    pub async fn tune(
        &mut self,
        data: &BindData,
        hop_index: u8,
    ) -> Result<(), Error<SPI::Error, IRQ::Error>> {
        for (address, value) in modem::hop_registers(data, hop_index).into_iter().flatten() {
            self.bus.write(address, value).await.map_err(Error::Radio)?;
        }
        Ok(())
    }

    /// Tunes a raw channel number (0x79) without touching the header, for channel scans.
    pub async fn tune_channel_number(
        &mut self,
        channel: u8,
    ) -> Result<(), Error<SPI::Error, IRQ::Error>> {
        self.bus.write(0x79, channel).await.map_err(Error::Radio)
    }

    /// Reads the RSSI register (0x26) as it is now.
    pub async fn rssi(&mut self) -> Result<u8, Error<SPI::Error, IRQ::Error>> {
        self.bus.read(REG_RSSI).await.map_err(Error::Radio)
    }

    /// `rx_reset`: clears the FIFOs and enters RX.
    pub async fn listen(&mut self) -> Result<(), Error<SPI::Error, IRQ::Error>> {
        let script = modem::rx_reset_script(self.version, self.diversity).map_err(Error::Script)?;
        self.run(&script).await
    }

    /// `tx_packet`: sends one packet and waits for `packet sent` (up to 100 ms).
    pub async fn transmit(&mut self, packet: &[u8]) -> Result<(), Error<SPI::Error, IRQ::Error>> {
        let script = modem::tx_packet_script(packet).map_err(Error::Script)?;
        self.run(&script).await?;
        let give_up = self.clock.now_us() + TX_TIMEOUT_US;
        loop {
            if !self.wait_irq_until(give_up).await? {
                // Back to READY, as tx_done() does on timeout.
                self.bus.write(0x07, 0x01).await.map_err(Error::Radio)?;
                return Err(Error::TxTimeout);
            }
            let [status1, _] = self.read_status().await?;
            if status1 & IPKSENT != 0 {
                return Ok(());
            }
        }
    }

    /// Waits until a valid packet arrives or `deadline_us` passes (`None`). The radio must
    /// be listening; CRC failures re-arm the receiver and keep waiting.
    pub async fn receive_until(
        &mut self,
        deadline_us: u64,
    ) -> Result<Option<Received>, Error<SPI::Error, IRQ::Error>> {
        loop {
            if !self.wait_irq_until(deadline_us).await? {
                return Ok(None);
            }
            let [status1, _] = self.read_status().await?;
            if status1 & IPKVALID != 0 {
                let len = usize::from(self.bus.read(REG_RX_LEN).await.map_err(Error::Radio)?)
                    .min(MAX_PACKET_LEN);
                let mut buf = [0u8; MAX_PACKET_LEN];
                let bytes = buf.get_mut(..len).unwrap_or_default();
                self.bus
                    .read_burst(REG_FIFO, bytes)
                    .await
                    .map_err(Error::Radio)?;
                let rssi = self.bus.read(REG_RSSI).await.map_err(Error::Radio)?;
                let mut afc_regs = [0u8; 2];
                self.bus
                    .read_burst(REG_AFC, &mut afc_regs)
                    .await
                    .map_err(Error::Radio)?;
                let [afc_hi, afc_lo] = afc_regs;
                let afc = (u16::from(afc_hi) << 2) | (u16::from(afc_lo) >> 6);
                let at_us = self.clock.now_us();
                return Ok(Some(Received {
                    bytes: Vec::from_slice(bytes).unwrap_or_default(),
                    rssi,
                    afc,
                    at_us,
                }));
            }
            if status1 & ICRCERROR != 0 {
                self.listen().await?;
            }
        }
    }

    /// Sleeps until `deadline_us` (returns at once if it has passed).
    pub async fn delay_until(&mut self, deadline_us: u64) {
        let now = self.clock.now_us();
        if deadline_us > now {
            self.delay
                .delay_us(u32::try_from(deadline_us - now).unwrap_or(u32::MAX))
                .await;
        }
    }

    async fn read_status(&mut self) -> Result<[u8; 2], Error<SPI::Error, IRQ::Error>> {
        let mut status = [0u8; 2];
        self.bus
            .read_burst(0x03, &mut status)
            .await
            .map_err(Error::Radio)?;
        Ok(status)
    }

    /// Waits for nIRQ low or the deadline; `true` if nIRQ fired.
    async fn wait_irq_until(
        &mut self,
        deadline_us: u64,
    ) -> Result<bool, Error<SPI::Error, IRQ::Error>> {
        let now = self.clock.now_us();
        if now >= deadline_us {
            return Ok(false);
        }
        let wait_us = u32::try_from(deadline_us - now).unwrap_or(u32::MAX);
        match select(self.irq.wait_for_low(), self.delay.delay_us(wait_us)).await {
            Either::First(result) => result.map(|()| true).map_err(Error::Irq),
            Either::Second(()) => Ok(false),
        }
    }
}
