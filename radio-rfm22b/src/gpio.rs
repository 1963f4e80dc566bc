//! GPIO pin functions (0x0B–0x0D; datasheet, "GPIO Configuration"): the antenna switch wiring of
//! RFM22B-style modules and GPIO2's function. Pure.

/// GPIO function codes (bits 4:0 of 0x0B–0x0D).
const TX_STATE: u8 = 0x12;
const RX_STATE: u8 = 0x15;
const CLEAR_CHANNEL: u8 = 0x1C;
const VDD: u8 = 0x1D;

/// How the module's RF switch is wired to GPIO0/GPIO1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AntennaSwitch {
    /// RFM22B default: GPIO0 high in TX, GPIO1 high in RX.
    Gpio0TxGpio1Rx,
    /// Swapped (Revo rev 2, OpenLRSng `SWAP_GPIOS` boards): GPIO0 = RX, GPIO1 = TX.
    Gpio0RxGpio1Tx,
}

/// What GPIO2 outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Gpio2 {
    /// Clear-channel assessment (RSSI above 0x27), as Tau Labs.
    ClearChannel,
    /// Tied high (VDD), as OpenLRSng.
    Vdd,
    /// A raw 0x0D value, drive bits included (OpenLRSng writes 0xFD: drive 3, VDD).
    Raw(u8),
}

/// GPIO configuration: the antenna switch, GPIO2 and the drive strength (0–3) of all three.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GpioConfig {
    /// RF switch wiring.
    pub antenna_switch: AntennaSwitch,
    /// GPIO2 function.
    pub gpio2: Gpio2,
    /// Output drive strength 0–3 (bits 7:6); Tau Labs uses 3, OpenLRSng 0.
    pub drive: u8,
}

impl Default for GpioConfig {
    fn default() -> Self {
        Self::RFM22B
    }
}

impl GpioConfig {
    /// The RFM22B module wiring as Tau Labs drives it: GPIO0 = TX state, GPIO1 = RX state,
    /// GPIO2 = clear-channel output, drive strength 3.
    pub const RFM22B: Self = Self {
        antenna_switch: AntennaSwitch::Gpio0TxGpio1Rx,
        gpio2: Gpio2::ClearChannel,
        drive: 3,
    };

    /// Registers 0x0B, 0x0C, 0x0D.
    pub const fn registers(&self) -> [u8; 3] {
        let drive = (self.drive & 0x03) << 6;
        let (gpio0, gpio1) = match self.antenna_switch {
            AntennaSwitch::Gpio0TxGpio1Rx => (TX_STATE, RX_STATE),
            AntennaSwitch::Gpio0RxGpio1Tx => (RX_STATE, TX_STATE),
        };
        let gpio2 = match self.gpio2 {
            Gpio2::ClearChannel => drive | CLEAR_CHANNEL,
            Gpio2::Vdd => drive | VDD,
            Gpio2::Raw(value) => value,
        };
        [drive | gpio0, drive | gpio1, gpio2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_wirings() {
        // Tau Labs: 0x0B=D2 0x0C=D5 0x0D=DC; swapped D5/D2.
        let tau = GpioConfig::default();
        assert_eq!(tau.registers(), [0xD2, 0xD5, 0xDC]);
        let swapped = GpioConfig {
            antenna_switch: AntennaSwitch::Gpio0RxGpio1Tx,
            ..tau
        };
        assert_eq!(swapped.registers(), [0xD5, 0xD2, 0xDC]);
        // OpenLRSng: 0x0B=12 0x0C=15 (drive 0), GPIO2 0xFD (drive 3 | VDD).
        let openlrs = GpioConfig {
            antenna_switch: AntennaSwitch::Gpio0TxGpio1Rx,
            gpio2: Gpio2::Raw(0xFD),
            drive: 0,
        };
        assert_eq!(openlrs.registers(), [0x12, 0x15, 0xFD]);
        let vdd = GpioConfig {
            gpio2: Gpio2::Vdd,
            ..openlrs
        };
        assert_eq!(vdd.registers(), [0x12, 0x15, 0x1D]);
    }
}
