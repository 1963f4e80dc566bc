//! How OpenLRSng programs the Si4432: its own five modem profiles (not recomputed — they are
//! OpenLRSng's table, air compatibility depends on them), `init_rfm`, `rx_reset`,
//! `tx_packet_async`, the carrier and hop-channel registers (Si4432
//! datasheet §3.5 for the frequency registers).

use heapless::Vec;

use super::bind::BindData;
use super::version::BindingVersion;
use crate::RfmType;

/// Registers a modem profile sets, in the order `setModemRegs()` writes them.
pub const MODEM_REGISTERS: [u8; 15] = [
    0x1C, 0x1D, 0x1E, 0x20, 0x21, 0x22, 0x23, 0x24, 0x25, 0x2A, 0x6E, 0x6F, 0x70, 0x71, 0x72,
];

/// One row of OpenLRSng's `modem_params[]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModemProfile {
    /// Air bit rate, used by the interval formula.
    pub bps: u32,
    /// Values for [`MODEM_REGISTERS`], same order.
    pub values: [u8; 15],
}

/// `modem_params[0..5]`: 4800, 9600, 19200, 57600 and 125000 bps.
pub const PROFILES: [ModemProfile; 5] = [
    ModemProfile {
        bps: 4800,
        values: [
            0x1A, 0x40, 0x0A, 0xA1, 0x20, 0x4E, 0xA5, 0x00, 0x1B, 0x1E, 0x27, 0x52, 0x2C, 0x23,
            0x30,
        ],
    },
    ModemProfile {
        bps: 9600,
        values: [
            0x05, 0x40, 0x0A, 0xA1, 0x20, 0x4E, 0xA5, 0x00, 0x20, 0x24, 0x4E, 0xA5, 0x2C, 0x23,
            0x30,
        ],
    },
    ModemProfile {
        bps: 19200,
        values: [
            0x06, 0x40, 0x0A, 0xD0, 0x00, 0x9D, 0x49, 0x00, 0x7B, 0x28, 0x9D, 0x49, 0x2C, 0x23,
            0x30,
        ],
    },
    ModemProfile {
        bps: 57600,
        values: [
            0x05, 0x40, 0x0A, 0x45, 0x01, 0xD7, 0xDC, 0x03, 0xB8, 0x1E, 0x0E, 0xBF, 0x00, 0x23,
            0x2E,
        ],
    },
    ModemProfile {
        bps: 125_000,
        values: [
            0x8A, 0x40, 0x0A, 0x60, 0x01, 0x55, 0x55, 0x02, 0xAD, 0x1E, 0x20, 0x00, 0x00, 0x23,
            0xC8,
        ],
    },
];

/// `bind_params`: the 9600 bps profile used on the bind channel.
pub const BIND_PROFILE: ModemProfile = PROFILES[1];

/// Looks a `bind_data.modem_params` index up.
pub fn profile(index: u8) -> Option<&'static ModemProfile> {
    PROFILES.get(usize::from(index))
}

/// One SPI access as OpenLRSng performs it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RegOp {
    /// Write `value` to register `address`.
    Write {
        /// Register address 0x00..0x7F.
        address: u8,
        /// Value written.
        value: u8,
    },
    /// Read register `address` (only for its side effect, e.g. clearing interrupt status).
    Read {
        /// Register address.
        address: u8,
    },
}

/// Capacity of a register script (init is 53 writes + 2 reads; a TX of 22 bytes is 28).
pub const SCRIPT_CAPACITY: usize = 64;
/// An ordered list of register accesses.
pub type Script = Vec<RegOp, SCRIPT_CAPACITY>;

/// What `init_rfm` prepares the radio for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Purpose {
    /// `init_rfm(1)`: bind profile, BIND_MAGIC, power 6, binding frequency.
    Bind,
    /// `init_rfm(0)`: the bound link's profile, magic, power and carrier.
    Link,
}

/// `BINDING_POWER`: not the lowest, since that may fail with RFM23BP boosters.
pub const BINDING_POWER: u8 = 0x06;

/// `rfmSetCarrierFrequency(f)`: registers 0x75 (band select), 0x76/0x77 (fc), datasheet
/// §3.5.1: below 480 MHz steps are 10 MHz / 64000 (hbsel 0), above 20 MHz / 64000.
pub fn carrier_registers(frequency_hz: u32) -> [(u8, u8); 3] {
    let (hbsel, band_hz, fc_per_hz_num) = if frequency_hz < 480_000_000 {
        (0u8, 10_000_000u32, 4u32)
    } else {
        (0x20u8, 20_000_000u32, 2u32)
    };
    let fb = (frequency_hz / band_hz).wrapping_sub(24);
    let base_hz = fb.wrapping_add(24).wrapping_mul(band_hz);
    // OpenLRSng stores fc in a uint16_t; the wrapping arithmetic reproduces its truncation.
    let fc = (frequency_hz
        .wrapping_sub(base_hz)
        .wrapping_mul(fc_per_hz_num)
        / 625) as u16;
    let [fc_hi, fc_lo] = fc.to_be_bytes();
    [
        (0x75, 0x40 + hbsel + (fb as u8 & 0x1F)),
        (0x76, fc_hi),
        (0x77, fc_lo),
    ]
}

/// The on-air header for a hop index: `rf_magic` big-endian with the last byte XORed with
/// the index (`rfmSetChannel`), so packets of another hop slot fail the header check.
pub fn link_header(rf_magic: u32, hop_index: u8) -> [u8; 4] {
    let [a, b, c, d] = rf_magic.to_be_bytes();
    [a, b, c, d ^ hop_index]
}

/// `rfmSetChannel(i)`: 0x79 = hop channel, 0x3D (TX header 0) and 0x42 (check header 0) =
/// `(rf_magic & 0xFF) ^ i`. Returns `None` past the 24-entry list.
pub fn hop_registers(data: &BindData, hop_index: u8) -> Option<[(u8, u8); 3]> {
    let channel = *data.hop_channels.get(usize::from(hop_index))?;
    let magic_lsb = (data.rf_magic & 0xFF) as u8 ^ hop_index;
    Some([(0x79, channel), (0x3D, magic_lsb), (0x42, magic_lsb)])
}

/// The frequency of a hop slot: `rf_frequency + channel · spacing · 10 kHz`. `None` past the
/// 24-entry list, or when the sum does not fit a `u32` (bind data that
/// [`BindData::validate`] refuses).
pub fn hop_frequency_hz(data: &BindData, hop_index: u8) -> Option<u32> {
    let channel = *data.hop_channels.get(usize::from(hop_index))?;
    u32::try_from(data.channel_frequency_hz(channel)).ok()
}

/// Appends a write, failing only if the script overflows (it is sized for the worst case).
fn w(script: &mut Script, address: u8, value: u8) -> Result<(), Error> {
    script
        .push(RegOp::Write { address, value })
        .map_err(|_| Error::ScriptFull)
}

fn r(script: &mut Script, address: u8) -> Result<(), Error> {
    script
        .push(RegOp::Read { address })
        .map_err(|_| Error::ScriptFull)
}

fn modem_writes(script: &mut Script, p: &ModemProfile) -> Result<(), Error> {
    for (&address, &value) in MODEM_REGISTERS.iter().zip(p.values.iter()) {
        w(script, address, value)?;
    }
    Ok(())
}

fn header_writes(script: &mut Script, magic: u32) -> Result<(), Error> {
    // TX header 0x3A+i and check header 0x3F+i interleaved, MSB first, as init_rfm does.
    for (i, byte) in (0u8..).zip(magic.to_be_bytes()) {
        w(script, 0x3A + i, byte)?;
        w(script, 0x3F + i, byte)?;
    }
    Ok(())
}

/// `init_rfm(isbind)` as the chosen OpenLRSng generation performs it, write for write.
///
/// Differences: 3.9 also clears 0x05 and writes GPIO2 (0x0D) = 0x17 when diversity is on;
/// 3.8.9 writes 0x0D = 0x17 only on boards built with `ANTENNA_DIVERSITY`, which this
/// models as not set. Both use an 80-bit preamble (0x34 = 0x14) with diversity.
pub fn init_script(
    version: BindingVersion,
    band: RfmType,
    data: &BindData,
    purpose: Purpose,
) -> Result<Script, Error> {
    let (profile, magic, power, frequency_hz) = match purpose {
        Purpose::Bind => (
            &BIND_PROFILE,
            version.bind_magic(),
            BINDING_POWER,
            band.binding_frequency_hz(),
        ),
        Purpose::Link => (
            {
                // Never tune a carrier or a hop outside the module's band plan.
                data.validate_for(band).map_err(Error::BindData)?;
                profile(data.modem_profile).ok_or(Error::ModemProfile(data.modem_profile))?
            },
            data.rf_magic,
            data.rf_power,
            data.rf_frequency_hz,
        ),
    };
    let preamble = if data.diversity() { 0x14 } else { 0x0A };
    let mut s = Script::new();
    // Clear pending interrupt status first (ItStatus1/2).
    r(&mut s, 0x03)?;
    r(&mut s, 0x04)?;
    match version {
        BindingVersion::V39 => {
            let gpio2 = if data.diversity() { 0x17 } else { 0xFD };
            for (a, v) in [
                (0x07, 0x01),
                (0x06, 0x00),
                (0x05, 0x00),
                (0x09, 0x7F),
                (0x0A, 0x05),
            ] {
                w(&mut s, a, v)?;
            }
            for (a, v) in [
                (0x0D, gpio2),
                (0x34, preamble),
                (0x0E, 0x00),
                (0x0B, 0x12),
                (0x0C, 0x15),
            ] {
                w(&mut s, a, v)?;
            }
            for (a, v) in [(0x30, 0x8C), (0x32, 0x0F), (0x33, 0x42), (0x35, 0x2A)] {
                w(&mut s, a, v)?;
            }
            for (a, v) in [(0x36, 0x2D), (0x37, 0xD4), (0x38, 0x00), (0x39, 0x00)] {
                w(&mut s, a, v)?;
            }
            for a in 0x43..=0x46 {
                w(&mut s, a, 0xFF)?;
            }
            for (a, v) in [
                (0x73, 0x00),
                (0x74, 0x00),
                (0x79, 0x00),
                (0x7A, data.rf_channel_spacing),
            ] {
                w(&mut s, a, v)?;
            }
            header_writes(&mut s, magic)?;
            modem_writes(&mut s, profile)?;
            w(&mut s, 0x6D, power)?;
        }
        BindingVersion::V38 => {
            for (a, v) in [(0x06, 0x00), (0x07, 0x01), (0x09, 0x7F), (0x0A, 0x05)] {
                w(&mut s, a, v)?;
            }
            for (a, v) in [(0x0B, 0x12), (0x0C, 0x15), (0x0D, 0xFD), (0x0E, 0x00)] {
                w(&mut s, a, v)?;
            }
            modem_writes(&mut s, profile)?;
            for (a, v) in [
                (0x30, 0x8C),
                (0x32, 0x0F),
                (0x33, 0x42),
                (0x34, preamble),
                (0x35, 0x2A),
            ] {
                w(&mut s, a, v)?;
            }
            for (a, v) in [(0x36, 0x2D), (0x37, 0xD4), (0x38, 0x00), (0x39, 0x00)] {
                w(&mut s, a, v)?;
            }
            header_writes(&mut s, magic)?;
            for a in 0x43..=0x46 {
                w(&mut s, a, 0xFF)?;
            }
            w(&mut s, 0x6D, power)?;
            for (a, v) in [
                (0x79, 0x00),
                (0x7A, data.rf_channel_spacing),
                (0x73, 0x00),
                (0x74, 0x00),
            ] {
                w(&mut s, a, v)?;
            }
        }
    }
    for (a, v) in carrier_registers(frequency_hz) {
        w(&mut s, a, v)?;
    }
    Ok(s)
}

/// `rx_reset()`: clear the FIFOs, enter RX, enable the packet-received interrupt.
pub fn rx_reset_script(version: BindingVersion, diversity: bool) -> Result<Script, Error> {
    let (clear, unclear) = match (version, diversity) {
        (BindingVersion::V39, true) => (0x83, 0x80),
        _ => (0x03, 0x00),
    };
    let mut s = Script::new();
    match version {
        BindingVersion::V39 => {
            for (a, v) in [(0x08, clear), (0x08, unclear), (0x05, 0x02), (0x07, 0x05)] {
                w(&mut s, a, v)?;
            }
        }
        BindingVersion::V38 => {
            // 0x7E = 36: RX-almost-full threshold, set on every reset by 3.8.
            for (a, v) in [
                (0x07, 0x01),
                (0x7E, 36),
                (0x08, clear),
                (0x08, unclear),
                (0x07, 0x05),
                (0x05, 0x02),
            ] {
                w(&mut s, a, v)?;
            }
        }
    }
    r(&mut s, 0x03)?;
    r(&mut s, 0x04)?;
    Ok(s)
}

/// `tx_packet_async()`: length to 0x3E, bytes to the FIFO, packet-sent interrupt, TX on.
pub fn tx_packet_script(packet: &[u8]) -> Result<Script, Error> {
    let len = u8::try_from(packet.len()).map_err(|_| Error::ScriptFull)?;
    let mut s = Script::new();
    w(&mut s, 0x3E, len)?;
    for &byte in packet {
        w(&mut s, 0x7F, byte)?;
    }
    w(&mut s, 0x05, 0x04)?;
    r(&mut s, 0x03)?;
    r(&mut s, 0x04)?;
    w(&mut s, 0x07, 0x09)?;
    Ok(s)
}

/// `rfmSetPower(p)`.
pub fn power_write(power: u8) -> RegOp {
    RegOp::Write {
        address: 0x6D,
        value: power,
    }
}

/// Register scripting failures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The modem profile index is not 0..4.
    ModemProfile(u8),
    /// The script does not fit [`SCRIPT_CAPACITY`] (a packet over 58 bytes).
    ScriptFull,
    /// The bind data of the link fails [`BindData::validate_for`] the band.
    BindData(super::bind::Error),
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::ModemProfile(p) => write!(f, "modem profile {p} is not 0..4"),
            Self::ScriptFull => write!(f, "register script too long"),
            Self::BindData(e) => write!(f, "bind data: {e}"),
        }
    }
}

impl core::error::Error for Error {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn carrier_435_mhz() {
        // 435 MHz: fb = 19 → 0x53, fc = 5 MHz · 4/625 = 32000 = 0x7D00.
        assert_eq!(
            carrier_registers(435_000_000),
            [(0x75, 0x53), (0x76, 0x7D), (0x77, 0x00)]
        );
        assert_eq!(carrier_registers(868_000_000)[0], (0x75, 0x73));
    }

    #[test]
    fn header_xor() {
        assert_eq!(link_header(0xDEAD_FEED, 3), [0xDE, 0xAD, 0xFE, 0xEE]);
    }
}
