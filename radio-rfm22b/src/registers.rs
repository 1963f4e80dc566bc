//! Register addresses and bit fields of the Si4432 (datasheet register table,
//! and AN440 for the modem registers). Only what the driver uses is named here.

/// 0x00 Device Type: reads 0x08 on every Si4430/31/32 ("EZRadioPRO transceiver").
pub const DEVICE_TYPE: u8 = 0x00;
/// 0x01 Device Version.
pub const DEVICE_VERSION: u8 = 0x01;
/// 0x02 Device Status.
pub const DEVICE_STATUS: u8 = 0x02;
/// 0x03 Interrupt/Status 1 (read clears).
pub const INTERRUPT_STATUS_1: u8 = 0x03;
/// 0x04 Interrupt/Status 2 (read clears).
pub const INTERRUPT_STATUS_2: u8 = 0x04;
/// 0x05 Interrupt Enable 1.
pub const INTERRUPT_ENABLE_1: u8 = 0x05;
/// 0x06 Interrupt Enable 2.
pub const INTERRUPT_ENABLE_2: u8 = 0x06;
/// 0x07 Operating & Function Control 1.
pub const OPERATING_MODE_1: u8 = 0x07;
/// 0x08 Operating & Function Control 2 (FIFO clears, auto-TX, antenna diversity).
pub const OPERATING_MODE_2: u8 = 0x08;
/// 0x09 Crystal Oscillator Load Capacitance.
pub const CRYSTAL_LOAD: u8 = 0x09;
/// 0x0A Microcontroller Output Clock.
pub const MCU_CLOCK: u8 = 0x0A;
/// 0x0B GPIO0 Configuration.
pub const GPIO0_CONFIG: u8 = 0x0B;
/// 0x0C GPIO1 Configuration (also the "locked module" probe: reads 0 after a silent reset).
pub const GPIO1_CONFIG: u8 = 0x0C;
/// 0x0D GPIO2 Configuration.
pub const GPIO2_CONFIG: u8 = 0x0D;
/// 0x0E I/O Port Configuration.
pub const IO_PORT_CONFIG: u8 = 0x0E;
/// 0x0F ADC Configuration.
pub const ADC_CONFIG: u8 = 0x0F;
/// 0x10 ADC Sensor Amplifier Offset.
pub const ADC_AMP_OFFSET: u8 = 0x10;
/// 0x11 ADC Value.
pub const ADC_VALUE: u8 = 0x11;
/// 0x12 Temperature Sensor Control.
pub const TEMPERATURE_CONTROL: u8 = 0x12;
/// 0x13 Temperature Value Offset.
pub const TEMPERATURE_OFFSET: u8 = 0x13;
/// 0x1C IF Filter Bandwidth.
pub const IF_FILTER_BANDWIDTH: u8 = 0x1C;
/// 0x1D AFC Loop Gearshift Override.
pub const AFC_GEARSHIFT: u8 = 0x1D;
/// 0x1E AFC Timing Control.
pub const AFC_TIMING: u8 = 0x1E;
/// 0x1F Clock Recovery Gearshift Override.
pub const CLOCK_RECOVERY_GEARSHIFT: u8 = 0x1F;
/// 0x20 Clock Recovery Oversampling Ratio (`rxosr[7:0]`); 0x21–0x25 follow.
pub const CLOCK_RECOVERY_OVERSAMPLING: u8 = 0x20;
/// 0x26 Received Signal Strength Indicator.
pub const RSSI: u8 = 0x26;
/// 0x27 RSSI Threshold for Clear Channel Indicator.
pub const RSSI_THRESHOLD: u8 = 0x27;
/// 0x2A AFC Limiter.
pub const AFC_LIMITER: u8 = 0x2A;
/// 0x2B AFC Correction Read (`afc_corr[9:2]`).
pub const AFC_CORRECTION: u8 = 0x2B;
/// 0x2C OOK Counter Value 1 (bits 7:6 are `afc_corr[1:0]`).
pub const OOK_COUNTER_1: u8 = 0x2C;
/// 0x2D OOK Counter Value 2.
pub const OOK_COUNTER_2: u8 = 0x2D;
/// 0x30 Data Access Control (packet handler, CRC).
pub const DATA_ACCESS_CONTROL: u8 = 0x30;
/// 0x31 EZMAC Status (read-only): live packet-handler state.
pub const EZMAC_STATUS: u8 = 0x31;
/// 0x31 bit 4 pkrx: a packet is being received (sync and header accepted).
pub const EZMAC_PKRX: u8 = 1 << 4;
/// 0x32 Header Control 1 (broadcast enables, header checks).
pub const HEADER_CONTROL_1: u8 = 0x32;
/// 0x33 Header Control 2 (header length, fixed length, sync length, preamble bit 8).
pub const HEADER_CONTROL_2: u8 = 0x33;
/// 0x34 Preamble Length (nibbles, bits 7:0).
pub const PREAMBLE_LENGTH: u8 = 0x34;
/// 0x35 Preamble Detection Control.
pub const PREAMBLE_DETECTION: u8 = 0x35;
/// 0x36 Sync Word 3 (first on air); 0x37–0x39 follow.
pub const SYNC_WORD_3: u8 = 0x36;
/// 0x3A Transmit Header 3 (first on air); 0x3B–0x3D follow.
pub const TRANSMIT_HEADER_3: u8 = 0x3A;
/// 0x3E Transmit Packet Length.
pub const TRANSMIT_PACKET_LENGTH: u8 = 0x3E;
/// 0x3F Check Header 3; 0x40–0x42 follow.
pub const CHECK_HEADER_3: u8 = 0x3F;
/// 0x43 Header Enable 3; 0x44–0x46 follow.
pub const HEADER_ENABLE_3: u8 = 0x43;
/// 0x47 Received Header 3; 0x48–0x4A follow.
pub const RECEIVED_HEADER_3: u8 = 0x47;
/// 0x4B Received Packet Length.
pub const RECEIVED_PACKET_LENGTH: u8 = 0x4B;
/// 0x58 Charge-pump current trim (the calculator raises it above 100 kbps).
pub const CHARGE_PUMP_TRIM: u8 = 0x58;
/// 0x69 AGC Override 1.
pub const AGC_OVERRIDE: u8 = 0x69;
/// 0x6D TX Power.
pub const TX_POWER: u8 = 0x6D;
/// 0x6E TX Data Rate 1 (`txdr[15:8]`); 0x6F is `txdr[7:0]`.
pub const TX_DATA_RATE_1: u8 = 0x6E;
/// 0x70 Modulation Mode Control 1.
pub const MODULATION_MODE_1: u8 = 0x70;
/// 0x71 Modulation Mode Control 2.
pub const MODULATION_MODE_2: u8 = 0x71;
/// 0x72 Frequency Deviation (`fd[7:0]`).
pub const FREQUENCY_DEVIATION: u8 = 0x72;
/// 0x73 Frequency Offset 1; 0x74 Frequency Offset 2.
pub const FREQUENCY_OFFSET_1: u8 = 0x73;
/// 0x75 Frequency Band Select; 0x76/0x77 are the nominal carrier fc.
pub const FREQUENCY_BAND_SELECT: u8 = 0x75;
/// 0x79 Frequency Hopping Channel Select.
pub const HOP_CHANNEL: u8 = 0x79;
/// 0x7A Frequency Hopping Step Size (10 kHz units).
pub const HOP_STEP: u8 = 0x7A;
/// 0x7C TX FIFO Control 1 (almost-full threshold); 0x7D almost-empty; 0x7E RX almost-full.
pub const TX_FIFO_ALMOST_FULL: u8 = 0x7C;
/// 0x7F FIFO Access (bursts do not increment here).
pub const FIFO: u8 = 0x7F;

/// Value of [`DEVICE_TYPE`] & 0x1F on a genuine part.
pub const DEVICE_TYPE_SI443X: u8 = 0x08;

/// 0x07 bit 7: software register reset.
pub const MODE_SWRESET: u8 = 0x80;
/// 0x07 bit 3: TX on (returns to the idle state after the packet).
pub const MODE_TXON: u8 = 0x08;
/// 0x07 bit 2: RX on.
pub const MODE_RXON: u8 = 0x04;
/// 0x07 bit 1: PLL on (TUNE).
pub const MODE_PLLON: u8 = 0x02;
/// 0x07 bit 0: crystal on (READY).
pub const MODE_XTON: u8 = 0x01;

/// 0x08 bit 1: clear the RX FIFO (write 1 then 0).
pub const FFCLR_RX: u8 = 0x02;
/// 0x08 bit 0: clear the TX FIFO (write 1 then 0).
pub const FFCLR_TX: u8 = 0x01;

/// Interrupt/Status 1 bit 7: FIFO under/overflow.
pub const IRQ1_FIFO_ERROR: u8 = 0x80;
/// Interrupt/Status 1 bit 6: TX FIFO almost full.
pub const IRQ1_TX_ALMOST_FULL: u8 = 0x40;
/// Interrupt/Status 1 bit 5: TX FIFO almost empty.
pub const IRQ1_TX_ALMOST_EMPTY: u8 = 0x20;
/// Interrupt/Status 1 bit 4: RX FIFO almost full.
pub const IRQ1_RX_ALMOST_FULL: u8 = 0x10;
/// Interrupt/Status 1 bit 2: packet sent.
pub const IRQ1_PACKET_SENT: u8 = 0x04;
/// Interrupt/Status 1 bit 1: valid packet received.
pub const IRQ1_PACKET_VALID: u8 = 0x02;
/// Interrupt/Status 1 bit 0: CRC error.
pub const IRQ1_CRC_ERROR: u8 = 0x01;
/// Interrupt/Status 2 bit 7: sync word detected.
pub const IRQ2_SYNC_DETECTED: u8 = 0x80;
/// Interrupt/Status 2 bit 6: valid preamble detected.
pub const IRQ2_PREAMBLE_VALID: u8 = 0x40;
/// Interrupt/Status 2 bit 1: chip ready (crystal running).
pub const IRQ2_CHIP_READY: u8 = 0x02;
/// Interrupt/Status 2 bit 0: power-on reset.
pub const IRQ2_POWER_ON_RESET: u8 = 0x01;

/// 0x0F bit 7: write 1 to start a conversion; reads 1 when it is done.
pub const ADC_START: u8 = 0x80;
