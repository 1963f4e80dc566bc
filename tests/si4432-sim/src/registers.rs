//! The Si4432 register map as this model sees it: addresses, reset values and access kind.
//!
//! Written from the Si4430/31/32 rev B1 datasheet register summary ("Register Descriptions"
//! table), deliberately **not** imported from `radio-rfm22b`: a wrong constant in the driver
//! must show up as a failing test, not be mirrored here (the lora-rs fixture
//! rule).

/// Register addresses (datasheet names, shortened).
pub mod addr {
    /// 0x00 Device Type (reads 0x08: EZRadioPRO transceiver).
    pub const DEVICE_TYPE: u8 = 0x00;
    /// 0x01 Device Version (0x06 = rev B1).
    pub const DEVICE_VERSION: u8 = 0x01;
    /// 0x02 Device Status: ffovfl, ffunfl, rxffem, headerr, freqerr, cps\[1:0\].
    pub const DEVICE_STATUS: u8 = 0x02;
    /// 0x03 Interrupt Status 1 (read clears).
    pub const INTERRUPT_STATUS_1: u8 = 0x03;
    /// 0x04 Interrupt Status 2 (read clears).
    pub const INTERRUPT_STATUS_2: u8 = 0x04;
    /// 0x05 Interrupt Enable 1.
    pub const INTERRUPT_ENABLE_1: u8 = 0x05;
    /// 0x06 Interrupt Enable 2.
    pub const INTERRUPT_ENABLE_2: u8 = 0x06;
    /// 0x07 Operating & Function Control 1: swres, enlbd, enwt, x32ksel, txon, rxon, pllon, xton.
    pub const OPERATING_MODE_1: u8 = 0x07;
    /// 0x08 Operating & Function Control 2: antdiv, rxmpk, autotx, enldm, ffclrrx, ffclrtx.
    pub const OPERATING_MODE_2: u8 = 0x08;
    /// 0x09 Crystal Oscillator Load Capacitance.
    pub const CRYSTAL_LOAD: u8 = 0x09;
    /// 0x0C GPIO1 Configuration (reads 0 after a reset: the "locked module" check).
    pub const GPIO1_CONFIG: u8 = 0x0C;
    /// 0x0F ADC Configuration (bit 7: adcstart on write, adcdone on read).
    pub const ADC_CONFIG: u8 = 0x0F;
    /// 0x11 ADC Value.
    pub const ADC_VALUE: u8 = 0x11;
    /// 0x12 Temperature Sensor Control.
    pub const TEMPERATURE_CONTROL: u8 = 0x12;
    /// 0x13 Temperature Value Offset.
    pub const TEMPERATURE_OFFSET: u8 = 0x13;
    /// 0x1B Battery Voltage Level.
    pub const BATTERY_LEVEL: u8 = 0x1B;
    /// 0x1C IF Filter Bandwidth: dwn3_bypass, ndec_exp\[2:0\], filset\[3:0\].
    pub const IF_FILTER_BANDWIDTH: u8 = 0x1C;
    /// 0x1D AFC Loop Gearshift Override (bit 6 enafc).
    pub const AFC_GEARSHIFT: u8 = 0x1D;
    /// 0x20 Clock Recovery Oversampling Rate (rxosr\[7:0\]).
    pub const CLOCK_RECOVERY_OVERSAMPLING: u8 = 0x20;
    /// 0x21 Clock Recovery Offset 2 (rxosr\[10:8\], stallctrl, ncoff\[19:16\]).
    pub const CLOCK_RECOVERY_OFFSET_2: u8 = 0x21;
    /// 0x22 Clock Recovery Offset 1 (ncoff\[15:8\]).
    pub const CLOCK_RECOVERY_OFFSET_1: u8 = 0x22;
    /// 0x23 Clock Recovery Offset 0 (ncoff\[7:0\]).
    pub const CLOCK_RECOVERY_OFFSET_0: u8 = 0x23;
    /// 0x26 Received Signal Strength Indicator.
    pub const RSSI: u8 = 0x26;
    /// 0x27 RSSI Threshold for Clear Channel Indicator (same units as 0x26).
    pub const RSSI_THRESHOLD: u8 = 0x27;
    /// 0x2A AFC Limiter.
    pub const AFC_LIMITER: u8 = 0x2A;
    /// 0x2B AFC Correction Read (bits 9..2 of the 10-bit correction).
    pub const AFC_CORRECTION: u8 = 0x2B;
    /// 0x2C OOK Counter Value 1 (bits 7:6 hold AFC correction bits 1..0 on read).
    pub const OOK_COUNTER_1: u8 = 0x2C;
    /// 0x30 Data Access Control: enpacrx, lsbfrst, crcdonly, skip2ph, enpactx, encrc, crc\[1:0\].
    pub const DATA_ACCESS_CONTROL: u8 = 0x30;
    /// 0x31 EzMAC status: rxcrc1, pksrch, pkrx, pkvalid, crcerror, pktx, pksent.
    pub const EZMAC_STATUS: u8 = 0x31;
    /// 0x32 Header Control 1: bcen\[3:0\], hdch\[3:0\].
    pub const HEADER_CONTROL_1: u8 = 0x32;
    /// 0x33 Header Control 2: skipsyn, hdlen\[2:0\], fixpklen, synclen\[1:0\], prealen\[8\].
    pub const HEADER_CONTROL_2: u8 = 0x33;
    /// 0x34 Preamble Length (prealen\[7:0\], in nibbles).
    pub const PREAMBLE_LENGTH: u8 = 0x34;
    /// 0x35 Preamble Detection Control: preath\[4:0\] (nibbles), rssi_off\[2:0\].
    pub const PREAMBLE_DETECTION: u8 = 0x35;
    /// 0x36 Sync Word 3 (first on air); 0x37..0x39 are sync words 2..0.
    pub const SYNC_WORD_3: u8 = 0x36;
    /// 0x3A Transmit Header 3 (first on air); 0x3B..0x3D are headers 2..0.
    pub const TRANSMIT_HEADER_3: u8 = 0x3A;
    /// 0x3E Transmit Packet Length (also the RX length when fixpklen = 1).
    pub const TRANSMIT_PACKET_LENGTH: u8 = 0x3E;
    /// 0x3F Check Header 3; 0x40..0x42 are check headers 2..0.
    pub const CHECK_HEADER_3: u8 = 0x3F;
    /// 0x43 Header Enable 3; 0x44..0x46 are header enables 2..0.
    pub const HEADER_ENABLE_3: u8 = 0x43;
    /// 0x47 Received Header 3; 0x48..0x4A are received headers 2..0.
    pub const RECEIVED_HEADER_3: u8 = 0x47;
    /// 0x4B Received Packet Length.
    pub const RECEIVED_PACKET_LENGTH: u8 = 0x4B;
    /// 0x6D TX Power: lna_sw (bit 3), txpow\[2:0\].
    pub const TX_POWER: u8 = 0x6D;
    /// 0x6E TX Data Rate 1 (txdr\[15:8\]).
    pub const TX_DATA_RATE_1: u8 = 0x6E;
    /// 0x6F TX Data Rate 0 (txdr\[7:0\]).
    pub const TX_DATA_RATE_0: u8 = 0x6F;
    /// 0x70 Modulation Mode Control 1: txdtrtscale, enphpwdn, manppol, enmaninv, enmanch, enwhite.
    pub const MODULATION_CONTROL_1: u8 = 0x70;
    /// 0x71 Modulation Mode Control 2: trclk, dtmod, eninv, fd\[8\], modtyp.
    pub const MODULATION_CONTROL_2: u8 = 0x71;
    /// 0x72 Frequency Deviation (fd\[7:0\], 625 Hz steps).
    pub const FREQUENCY_DEVIATION: u8 = 0x72;
    /// 0x73 Frequency Offset 1 (fo\[7:0\]).
    pub const FREQUENCY_OFFSET_1: u8 = 0x73;
    /// 0x74 Frequency Offset 2 (fo\[9:8\]).
    pub const FREQUENCY_OFFSET_2: u8 = 0x74;
    /// 0x75 Frequency Band Select: sbsel, hbsel, fb\[4:0\].
    pub const FREQUENCY_BAND: u8 = 0x75;
    /// 0x76 Nominal Carrier Frequency 1 (fc\[15:8\]).
    pub const CARRIER_FREQUENCY_1: u8 = 0x76;
    /// 0x77 Nominal Carrier Frequency 0 (fc\[7:0\]).
    pub const CARRIER_FREQUENCY_0: u8 = 0x77;
    /// 0x79 Frequency Hopping Channel Select.
    pub const HOPPING_CHANNEL: u8 = 0x79;
    /// 0x7A Frequency Hopping Step Size (10 kHz units).
    pub const HOPPING_STEP: u8 = 0x7A;
    /// 0x7C TX FIFO Control 1: TX almost-full threshold.
    pub const TX_FIFO_CONTROL_1: u8 = 0x7C;
    /// 0x7D TX FIFO Control 2: TX almost-empty threshold.
    pub const TX_FIFO_CONTROL_2: u8 = 0x7D;
    /// 0x7E RX FIFO Control: RX almost-full threshold.
    pub const RX_FIFO_CONTROL: u8 = 0x7E;
    /// 0x7F FIFO Access (write: TX FIFO, read: RX FIFO; no address auto-increment).
    pub const FIFO_ACCESS: u8 = 0x7F;
}

/// Interrupt Status 1 / Enable 1 bits (0x03 / 0x05).
pub mod irq1 {
    /// FIFO underflow/overflow error.
    pub const FIFO_ERROR: u8 = 1 << 7;
    /// TX FIFO almost full.
    pub const TX_FIFO_ALMOST_FULL: u8 = 1 << 6;
    /// TX FIFO almost empty.
    pub const TX_FIFO_ALMOST_EMPTY: u8 = 1 << 5;
    /// RX FIFO almost full.
    pub const RX_FIFO_ALMOST_FULL: u8 = 1 << 4;
    /// External interrupt (not modelled).
    pub const EXTERNAL: u8 = 1 << 3;
    /// Packet sent.
    pub const PACKET_SENT: u8 = 1 << 2;
    /// Valid packet received.
    pub const VALID_PACKET: u8 = 1 << 1;
    /// CRC error.
    pub const CRC_ERROR: u8 = 1 << 0;
}

/// Interrupt Status 2 / Enable 2 bits (0x04 / 0x06).
pub mod irq2 {
    /// Sync word detected.
    pub const SYNC_WORD: u8 = 1 << 7;
    /// Valid preamble detected.
    pub const VALID_PREAMBLE: u8 = 1 << 6;
    /// Invalid preamble (not modelled).
    pub const INVALID_PREAMBLE: u8 = 1 << 5;
    /// RSSI at or above the 0x27 threshold.
    pub const RSSI: u8 = 1 << 4;
    /// Wake-up timer (not modelled).
    pub const WAKE_UP_TIMER: u8 = 1 << 3;
    /// Low battery (not modelled).
    pub const LOW_BATTERY: u8 = 1 << 2;
    /// Chip ready (crystal stable).
    pub const CHIP_READY: u8 = 1 << 1;
    /// Power-on reset.
    pub const POWER_ON_RESET: u8 = 1 << 0;
}

/// Operating & Function Control 1 bits (0x07).
pub mod mode1 {
    /// Software register reset.
    pub const SWRES: u8 = 1 << 7;
    /// Wake-up timer enable (SLEEP mode when nothing else is on).
    pub const ENWT: u8 = 1 << 5;
    /// TX on.
    pub const TXON: u8 = 1 << 3;
    /// RX on.
    pub const RXON: u8 = 1 << 2;
    /// PLL on (TUNE).
    pub const PLLON: u8 = 1 << 1;
    /// Crystal on (READY).
    pub const XTON: u8 = 1 << 0;
}

/// What a register does on an SPI access.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Read-write configuration register.
    ReadWrite,
    /// Read-only: writes are ignored.
    ReadOnly,
    /// Reserved / test register this model does not implement: reads its reset value, keeps writes.
    Reserved,
}

/// Access kind of `address` (datasheet "R" / "R/W" column).
pub fn access(address: u8) -> Access {
    match address {
        0x00..=0x04
        | 0x11
        | 0x17
        | 0x18
        | 0x1B
        | 0x26
        | 0x28
        | 0x29
        | 0x2B
        | 0x31
        | 0x47..=0x4B => Access::ReadOnly,
        0x05..=0x10
        | 0x12..=0x16
        | 0x19
        | 0x1A
        | 0x1C..=0x25
        | 0x27
        | 0x2A
        | 0x2C..=0x2E
        | 0x30
        | 0x32..=0x46
        | 0x4F
        | 0x60
        | 0x62
        | 0x69
        | 0x6D..=0x77
        | 0x79
        | 0x7A
        | 0x7C..=0x7F => Access::ReadWrite,
        _ => Access::Reserved,
    }
}

/// Datasheet reset value of `address` (what it reads after power-on or `swres`).
///
/// Read-only registers whose content is live (status, RSSI, ADC) return 0 here; the chip
/// model computes them on read.
pub fn reset_value(address: u8) -> u8 {
    match address {
        0x00 => 0x08, // device type: EZRadioPRO transceiver
        0x01 => 0x06, // version: B1
        0x06 => 0x03, // enchiprdy | enpor
        0x07 => 0x01, // xton: READY
        0x09 => 0x7F,
        0x0A => 0x06,
        0x12 => 0x20,
        0x14 => 0x03,
        0x16 => 0x01,
        0x1A => 0x14,
        0x1C => 0x01,
        0x1D => 0x40,
        0x1E => 0x0A,
        0x1F => 0x03,
        0x20 => 0x64,
        0x21 => 0x01,
        0x22 => 0x47,
        0x23 => 0xAE,
        0x24 => 0x02,
        0x25 => 0x8F,
        0x27 => 0x1E,
        0x2C => 0x18,
        0x2D => 0xBC,
        0x2E => 0x26,
        0x30 => 0x8D, // packet handler RX+TX, CRC on, CRC-16 (IBM)
        0x32 => 0x0C,
        0x33 => 0x22, // header 3,2; sync 3,2
        0x34 => 0x08, // 8 nibbles = 4 bytes of preamble
        0x35 => 0x2A, // preath 5 nibbles, rssi_off 2
        0x36 => 0x2D,
        0x37 => 0xD4,
        0x43..=0x46 => 0xFF,
        0x4F => 0x10,
        0x62 => 0x24,
        0x69 => 0x20,
        0x6D => 0x18, // lna_sw, txpow 0 (+1 dBm)
        0x6E => 0x0A, // txdr 0x0A3D: 40 kbps
        0x6F => 0x3D,
        0x70 => 0x0C,
        0x72 => 0x20, // 32 × 625 Hz = 20 kHz
        0x75 => 0x75, // sbsel, hbsel, fb 21
        0x76 => 0xBB, // fc 0xBB80: 915 MHz
        0x77 => 0x80,
        0x7C => 0x37,
        0x7D => 0x04,
        0x7E => 0x37,
        _ => 0x00,
    }
}

/// The whole register file after a reset.
pub fn reset_file() -> [u8; 128] {
    let mut file = [0u8; 128];
    for (address, value) in (0u8..).zip(file.iter_mut()) {
        *value = reset_value(address);
    }
    file
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_and_key_reset_values() {
        let file = reset_file();
        assert_eq!(file[0x00], 0x08);
        assert_eq!(file[0x01], 0x06);
        assert_eq!(file[0x05], 0x00);
        assert_eq!(file[0x06], 0x03);
        assert_eq!(file[0x07], 0x01);
        assert_eq!(file[0x0C], 0x00);
        assert_eq!(file[0x30], 0x8D);
        assert_eq!(file[0x7C], 0x37);
        assert_eq!(file[0x7D], 0x04);
        assert_eq!(file[0x7F], 0x00);
    }

    #[test]
    fn access_classes() {
        assert_eq!(access(0x00), Access::ReadOnly);
        assert_eq!(access(0x03), Access::ReadOnly);
        assert_eq!(access(0x4B), Access::ReadOnly);
        assert_eq!(access(0x07), Access::ReadWrite);
        assert_eq!(access(0x7F), Access::ReadWrite);
        assert_eq!(access(0x50), Access::Reserved);
    }
}
