//! The driver on a Linux board (e.g. a Raspberry Pi): RFM22B on `/dev/spidev0.0`, nIRQ on
//! GPIO 25 of `/dev/gpiochip0`, SDN tied low. Sends a ping every second and listens for
//! an answer in between. Run on the Pi with
//! `cargo run -p radio-rfm22b --features linux --example linux_spidev`
//! (cross-compiling: see `examples/linux_openlrs_rx.rs`).
//!
//! The `linux` feature provides the async adapters for linux-embedded-hal
//! (`radio_rfm22b::linux`); `embassy_futures::block_on` runs the driver.

use radio_rfm22b::linux::{StdDelay, open_nirq, open_spidev};
use radio_rfm22b::{Carrier, Config, ModemConfig, PacketConfig, Rfm22b, RxOutcome};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let spi = open_spidev("/dev/spidev0.0", 4_000_000)?;
    let nirq = open_nirq("/dev/gpiochip0", 25)?;
    let config = Config::new(
        ModemConfig::new(57_600, 28_800),
        PacketConfig::new(),
        Carrier::new(434_000_000),
    );
    let mut radio = Rfm22b::new_without_sdn(spi, nirq, StdDelay);
    embassy_futures::block_on(async {
        let chip = radio.init(config).await?;
        println!("Si4432 rev {:?}", chip.version);
        let mut buf = [0u8; 255];
        loop {
            radio.transmit(b"ping", 100_000).await?;
            match radio.receive(&mut buf, 1_000_000).await? {
                RxOutcome::Packet(p) => println!(
                    "{:02x?} at {} dBm, AFC {} Hz",
                    buf.get(..p.len).unwrap_or_default(),
                    p.signal.rssi_dbm,
                    p.signal.afc_offset_hz
                ),
                other => println!("{other:?}"),
            }
        }
    })
}
