//! One RFM22B, two air protocols: the chip either runs TauLink through [`LinkRadio`] or is
//! lent, part by part, to an OpenLRSng [`Radio`] (whose roles program the chip their own
//! way), and taken back on the next TauLink step. Both firmwares and the host simulations
//! switch through this one adapter instead of taking the driver apart by hand.
//!

use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;

use radio_rfm22b::link::LinkRadio;
use radio_rfm22b::{Rfm22b, TxPower};

use crate::radio::{Clock, Radio};
use crate::{BindingVersion, RfmType};

/// Who has the chip.
enum Holder<SPI, IRQ, SDN, D, C> {
    /// The TauLink adapter (the clock waits for the next OpenLRSng step).
    TauLink(LinkRadio<SPI, IRQ, SDN, D>, C),
    /// An OpenLRSng radio; SDN stays here (the OpenLRSng roles never drive it).
    OpenLrs(Radio<SPI, IRQ, D, C>, SDN),
    /// Only while the parts move from one holder to the other.
    Moving,
}

/// The RFM22B for whichever protocol the next link step speaks.
pub struct DualRadio<SPI, IRQ, SDN, D, C> {
    holder: Holder<SPI, IRQ, SDN, D, C>,
    tx_power: TxPower,
    sdn_present: bool,
}

impl<SPI, IRQ, SDN, D, C> DualRadio<SPI, IRQ, SDN, D, C>
where
    SPI: SpiDevice,
    IRQ: Wait,
    D: DelayNs,
    C: Clock,
{
    /// The driver, transmitting TauLink at `tx_power`; `clock` is the OpenLRSng radio's
    /// microsecond clock (`radio::Clock`, e.g. `|| Instant::now().as_micros()`).
    pub fn new(radio: Rfm22b<SPI, IRQ, SDN, D>, tx_power: TxPower, clock: C) -> Self {
        let sdn_present = radio.sdn_present();
        Self {
            holder: Holder::TauLink(LinkRadio::new(radio, tx_power), clock),
            tx_power,
            sdn_present,
        }
    }

    /// Gives the driver and the clock back (taken back from OpenLRSng if it was lent).
    /// `None` never happens outside a move.
    pub fn release(self) -> Option<(Rfm22b<SPI, IRQ, SDN, D>, C)> {
        match self.holder {
            Holder::TauLink(link, clock) => Some((link.release(), clock)),
            Holder::OpenLrs(radio, sdn) => {
                let (spi, irq, delay, clock) = radio.release();
                let driver = Rfm22b::from_parts(spi, irq, sdn, self.sdn_present, delay);
                Some((driver, clock))
            }
            Holder::Moving => None,
        }
    }

    /// The chip as TauLink's radio (taken back from OpenLRSng if it was lent; the link
    /// configures it again on its first use). `None` never happens outside a move.
    pub fn taulink(&mut self) -> Option<&mut LinkRadio<SPI, IRQ, SDN, D>> {
        if let Holder::OpenLrs(..) = self.holder
            && let Holder::OpenLrs(radio, sdn) =
                core::mem::replace(&mut self.holder, Holder::Moving)
        {
            let (spi, irq, delay, clock) = radio.release();
            let driver = Rfm22b::from_parts(spi, irq, sdn, self.sdn_present, delay);
            self.holder = Holder::TauLink(LinkRadio::new(driver, self.tx_power), clock);
        }
        match &mut self.holder {
            Holder::TauLink(link, _) => Some(link),
            _ => None,
        }
    }

    /// The chip as an OpenLRSng radio speaking `version` on `band` (lent from TauLink, or
    /// rebuilt if it spoke another generation or band). `None` never happens outside a move.
    pub fn openlrs(
        &mut self,
        version: BindingVersion,
        band: RfmType,
    ) -> Option<&mut Radio<SPI, IRQ, D, C>> {
        let fits = matches!(&self.holder, Holder::OpenLrs(r, _)
            if r.version() == version && r.band() == band);
        if !fits {
            let (spi, irq, sdn, delay, clock) =
                match core::mem::replace(&mut self.holder, Holder::Moving) {
                    Holder::TauLink(link, clock) => {
                        let (spi, irq, sdn, delay) = link.release().release();
                        (spi, irq, sdn, delay, clock)
                    }
                    Holder::OpenLrs(radio, sdn) => {
                        let (spi, irq, delay, clock) = radio.release();
                        (spi, irq, sdn, delay, clock)
                    }
                    Holder::Moving => return None,
                };
            let radio = Radio::new(spi, irq, delay, clock, version, band);
            self.holder = Holder::OpenLrs(radio, sdn);
        }
        match &mut self.holder {
            Holder::OpenLrs(radio, _) => Some(radio),
            _ => None,
        }
    }
}
