//! An OpenLRSng receiver on a Raspberry Pi: RFM22B (433 MHz) on SPI0 CE0
//! (`/dev/spidev0.0`: SCK GPIO 11, MOSI GPIO 10, MISO GPIO 9, nSEL GPIO 8), nIRQ on GPIO 25,
//! SDN tied to GND. It waits for a 3.8 transmitter in bind mode, then prints the channels in
//! µs, serial bytes and failsafe; with no module on the bus it says so and retries.
//!
//! Cross-compile on a PC for a 64-bit Raspberry Pi OS (needs `gcc-aarch64-linux-gnu`):
//! ```sh
//! rustup target add aarch64-unknown-linux-gnu
//! CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc \
//!   cargo build -p openlrs-ng --release --target aarch64-unknown-linux-gnu \
//!   --example linux_openlrs_rx
//! scp target/aarch64-unknown-linux-gnu/release/examples/linux_openlrs_rx pi@raspberrypi:
//! ```
//! (32-bit Raspberry Pi OS: `armv7-unknown-linux-gnueabihf` and `arm-linux-gnueabihf-gcc`.)
//! On the Pi, enable SPI (`raspi-config` → Interface Options → SPI) and run it as a user in
//! the `spi` and `gpio` groups. Nothing is persisted: store the `Bound` data and pass it to
//! `Receiver::new` to skip binding at the next start.
//!
//! On any other OS it is an empty `main`.

#[cfg(target_os = "linux")]
mod pi {
    use std::time::Duration;

    use openlrs::channels::bits_to_us;
    use openlrs::radio::Radio;
    use openlrs::roles::{RxEvent, run_receiver};
    use openlrs::rx::{Config, Receiver};
    use openlrs::{BindingVersion, RfmType};
    use radio_rfm22b::linux::{StdDelay, monotonic_us, open_nirq, open_spidev};

    pub fn main() -> Result<(), Box<dyn std::error::Error>> {
        let spi = open_spidev("/dev/spidev0.0", 4_000_000)?;
        let nirq = open_nirq("/dev/gpiochip0", 25)?;
        let (version, band) = (BindingVersion::V38, RfmType::Mhz433);
        let mut radio = Radio::new(spi, nirq, StdDelay, monotonic_us, version, band);
        let mut rx = Receiver::new(Config::new(version, band), None);
        loop {
            let error =
                embassy_futures::block_on(run_receiver(&mut radio, &mut rx, |event| match event {
                    RxEvent::Bound(data) => println!("bound: magic {:08x}", data.rf_magic),
                    RxEvent::Channels { channels_bits, .. } => {
                        let us: Vec<u16> = channels_bits.iter().map(|&b| bits_to_us(b)).collect();
                        println!("{us:?}");
                    }
                    RxEvent::Serial(bytes) => println!("serial: {:02x?}", bytes.as_slice()),
                    RxEvent::FailsafeStarted => println!("link lost: failsafe"),
                }));
            // `NotAnSi4432` here means no module answers: check the wiring and power.
            eprintln!("radio error: {error}");
            std::thread::sleep(Duration::from_secs(1));
        }
    }
}

#[cfg(target_os = "linux")]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    pi::main()
}

#[cfg(not(target_os = "linux"))]
fn main() {}
