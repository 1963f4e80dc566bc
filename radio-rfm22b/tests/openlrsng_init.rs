//! The driver's `init`, configured like OpenLRSng, leaves the chip in the same register state
//! as OpenLRSng's own `init_rfm(0)` (`modem_registers.json`, both trees, all five profiles):
//! a recording SPI device replays the driver's writes into a register file.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)] // test code

mod common;

use common::spi::LowIrq;

use std::collections::BTreeMap;
use std::convert::Infallible;

use embassy_futures::block_on;
use embedded_hal_async::spi::{ErrorType, Operation, SpiDevice};
use radio_rfm22b::{
    AntennaSwitch, Carrier, ChannelSpacing, Config, Gpio2, GpioConfig, IfFilter, ModemConfig,
    ModemSettings, PacketConfig, Rfm22b, TxPower,
};

/// Keeps the last value written to each register; reads return a B1 chip that is ready.
#[derive(Default)]
struct RecordingSpi {
    registers: BTreeMap<u8, u8>,
}

impl ErrorType for RecordingSpi {
    type Error = Infallible;
}

impl SpiDevice for RecordingSpi {
    async fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Infallible> {
        let [Operation::Write([address]), data] = ops else {
            panic!("unexpected framing")
        };
        match data {
            Operation::Write(bytes) => {
                let start = *address & 0x7F;
                for (i, b) in bytes.iter().enumerate() {
                    // Bursts increment the address (not used on 0x7F here).
                    self.registers.insert(start + i as u8, *b);
                }
            }
            Operation::Read(buf) => {
                let answer: &[u8] = match *address {
                    0x00 => &[0x08, 0x06],
                    0x03 => &[0x00, 0x02],
                    _ => &[0, 0],
                };
                buf.copy_from_slice(&answer[..buf.len()]);
            }
            _ => panic!("unexpected operation"),
        }
        Ok(())
    }
}

struct NoDelay;
impl embedded_hal_async::delay::DelayNs for NoDelay {
    async fn delay_ns(&mut self, _ns: u32) {}
}

/// OpenLRSng's modem profiles as calculator inputs (see tests/modem_math.rs for why).
fn modem(rate: u32) -> ModemConfig {
    let settings = match rate {
        4_800 => ModemSettings::new(4_800, 30_000)
            .with_if_filter(IfFilter::from_register(0x1A).unwrap())
            .with_afc_limiter(0x1E),
        9_600 => ModemSettings::new(9_600, 30_000).with_rx_deviation_hz(50_000),
        19_200 => ModemSettings::new(19_200, 30_000).with_rx_deviation_hz(50_000),
        57_600 => ModemSettings::new(57_600, 28_800)
            .with_rx_deviation_hz(57_600)
            .with_if_filter(IfFilter::from_register(0x05).unwrap())
            .with_afc_limiter(0x1E)
            .with_manchester_inverted(false),
        125_000 => ModemSettings::new(125_000, 125_000)
            .with_afc_limiter(0x1E)
            .with_manchester_inverted(false),
        other => panic!("no profile {other}"),
    };
    ModemConfig::from_settings(settings)
}

#[test]
fn init_matches_openlrsng_init_rfm() {
    let json = common::load("openlrs", "modem_registers.json");
    let table = &json["modem_params_table"];
    let mut runs = 0;
    for tree in ["master", "v3.8.9"] {
        let all = json["init_rfm_normal"][tree].as_array().unwrap();
        assert_eq!(all.len(), 10);
        for (position, run) in all.iter().enumerate() {
            // The second five runs are built with DIVERSITY_ENABLED: a 20-nibble preamble, and
            // on master GPIO2 = 0x17 (antenna-diversity switch; v3.8.9 only on boards with
            // ANTENNA_DIVERSITY, README of the vectors).
            let diversity = position >= 5;
            let bind = &run["bind_data"];
            let index = run["modem_params"].as_u64().unwrap() as usize;
            let rate = table[index]["bps"].as_u64().unwrap() as u32;
            let magic = u32::from_str_radix(
                bind["rf_magic"].as_str().unwrap().trim_start_matches("0x"),
                16,
            )
            .unwrap()
            .to_be_bytes();
            let packet = PacketConfig::new()
                .with_preamble(if diversity { 20 } else { 10 }, 5)
                .with_rssi_offset(2)
                .with_header(magic, 4)
                .with_header_check(magic, [0xFF; 4], 0x0F, 0x00);
            let frequency = bind["rf_frequency"].as_u64().unwrap() as u32;
            let mut config = Config::new(modem(rate), packet, Carrier::new(frequency));
            config.channel_spacing = ChannelSpacing::from_10khz_steps(
                bind["rf_channel_spacing"].as_u64().unwrap() as u8,
            );
            config.tx_power = TxPower::from_step(bind["rf_power"].as_u64().unwrap() as u8);
            config.lna_switch = false;
            config.gpio = GpioConfig {
                antenna_switch: AntennaSwitch::Gpio0TxGpio1Rx,
                gpio2: Gpio2::Raw(if diversity && tree == "master" {
                    0x17
                } else {
                    0xFD
                }),
                drive: 0,
            };

            let mut radio = Rfm22b::new_without_sdn(RecordingSpi::default(), LowIrq, NoDelay);
            block_on(radio.init(config)).unwrap();
            let (spi, ..) = radio.release();

            let mut compared = 0;
            for (key, value) in run["final_state"].as_object().unwrap() {
                let address = u8::from_str_radix(key.trim_start_matches("0x"), 16).unwrap();
                if address == 0x0A {
                    // MCU clock output: OpenLRSng selects 2 MHz; the driver leaves the pin alone.
                    continue;
                }
                let ours = spi.registers.get(&address).copied();
                assert_eq!(
                    ours,
                    Some(value.as_u64().unwrap() as u8),
                    "{tree} run {position} (profile {index}): register {key}"
                );
                compared += 1;
            }
            assert!(
                compared >= 45,
                "{tree} profile {index}: only {compared} compared"
            );
            runs += 1;
        }
    }
    assert_eq!(runs, 20);
}
