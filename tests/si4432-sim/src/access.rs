//! What an SPI access does to each register: live and read-to-clear registers, FIFO
//! access, mode and FIFO-clear writes, read-only protection, faults.

use crate::chip::{Activity, Chip, Ctx, Fault, Power, STATUS_FFOVFL, STATUS_FFUNFL};
use crate::registers::{self, Access, addr, irq1};

impl Chip {
    /// What an SPI read of `address` returns (and its side effects). `live_rssi` is the RSSI
    /// register value the medium computes for this moment.
    pub fn spi_read(&mut self, address: u8, live_rssi: u8) -> u8 {
        if let Fault::Unplugged { miso } = self.fault {
            return miso;
        }
        if self.power != Power::On {
            return 0x00;
        }
        match address {
            addr::DEVICE_STATUS => {
                let cps = match self.activity {
                    Activity::Tx(_) => 0b10,
                    Activity::Rx(_) => 0b01,
                    _ => 0b00,
                };
                self.device_flags | (u8::from(self.rx_fifo.is_empty()) << 5) | cps
            }
            addr::INTERRUPT_STATUS_1 => core::mem::take(&mut self.status1),
            addr::INTERRUPT_STATUS_2 => core::mem::take(&mut self.status2),
            addr::RSSI => self.rssi_latch.unwrap_or(live_rssi),
            addr::AFC_CORRECTION => (self.afc_raw >> 2) as u8,
            addr::OOK_COUNTER_1 => ((self.afc_raw as u8 & 0x03) << 6) | (self.reg(address) & 0x3F),
            addr::EZMAC_STATUS => self.ezmac_status(),
            addr::ADC_VALUE => self.adc_value(),
            addr::BATTERY_LEVEL => ((self.physical.supply_v - 1.7) / 0.05)
                .round()
                .clamp(0.0, 31.0) as u8,
            addr::FIFO_ACCESS => match self.rx_fifo.pop(0).0 {
                Some(byte) => byte,
                None => {
                    self.status1 |= irq1::FIFO_ERROR;
                    self.device_flags |= STATUS_FFUNFL;
                    0x00
                }
            },
            _ => self.reg(address),
        }
    }

    /// What an SPI write of `value` to `address` does.
    pub fn spi_write(&mut self, address: u8, value: u8, now_ns: u64, ctx: &mut Ctx<'_>) {
        if matches!(self.fault, Fault::Unplugged { .. }) || self.power != Power::On {
            return;
        }
        match (address, registers::access(address)) {
            (_, Access::ReadOnly) => {}
            (addr::OPERATING_MODE_1, _) => self.write_mode(value, now_ns, ctx),
            (addr::OPERATING_MODE_2, _) => {
                // ffclrtx / ffclrrx: the FIFO is cleared while the bit is written as 1.
                if value & 0x01 != 0 {
                    self.tx_fifo.clear();
                }
                if value & 0x02 != 0 {
                    self.rx_fifo.clear();
                }
                if value & 0x03 != 0 {
                    self.device_flags &= !(STATUS_FFOVFL | STATUS_FFUNFL);
                }
                self.set_reg(address, value);
            }
            // adcstart: the conversion is instantaneous here, so adcdone reads back at once.
            (addr::ADC_CONFIG, _) => self.set_reg(address, value | 0x80),
            (addr::FIFO_ACCESS, _) => {
                let events = self
                    .tx_fifo
                    .push(value, self.reg(addr::TX_FIFO_CONTROL_1) & 0x3F);
                if events.error {
                    self.status1 |= irq1::FIFO_ERROR;
                    self.device_flags |= STATUS_FFOVFL;
                }
                if events.almost_full {
                    self.status1 |= irq1::TX_FIFO_ALMOST_FULL;
                }
            }
            _ => self.set_reg(address, value),
        }
    }

    fn ezmac_status(&self) -> u8 {
        let live = match &self.activity {
            Activity::Tx(_) => 1 << 1,
            Activity::Rx(rx) if rx.receiving() => 1 << 4,
            Activity::Rx(_) => 1 << 5,
            _ => 0,
        };
        live | self.ezmac_latched
    }

    /// Temperature sensor through the ADC (0x12 tsrange, entsoffs + 0x13 offset).
    fn adc_value(&self) -> u8 {
        let t = self.physical.temperature_c;
        let control = self.reg(addr::TEMPERATURE_CONTROL);
        let code = match control >> 6 {
            0b00 => (t + 64.0) * 2.0,      // −64…64 °C, 0.5 °C
            0b01 => t + 64.0,              // −64…192 °C, 1 °C
            0b10 => t * 1.8 + 32.0 + 40.0, // −40…216 °F, 1 °F
            _ => t * 2.0,                  // 0…128 °C, 0.5 °C
        };
        let offset = if control & 0x20 != 0 {
            f64::from(self.reg(addr::TEMPERATURE_OFFSET) as i8)
        } else {
            0.0
        };
        (code + offset).round().clamp(0.0, 255.0) as u8
    }
}
