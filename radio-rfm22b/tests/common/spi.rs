//! The SPI-transcript toolkit shared by the transcript tests: register read/write
//! transactions for embedded-hal-mock, nIRQ and delay doubles, and the init transcript of a
//! Tau Labs-style configuration. Expected bytes are written out from the Si4432 datasheet
//! (and AN440, its register descriptions) and from Tau Labs' `pios_rfm22b.c`, not computed
//! with the driver's own functions.
#![allow(
    dead_code,
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing
)] // test code

use core::convert::Infallible;

use embassy_futures::block_on;
use embedded_hal_mock::eh1::spi::{Mock, Transaction};
use radio_rfm22b::{
    Carrier, ChannelSpacing, Config, Crc, ModemConfig, NoPin, PacketConfig, Rfm22b, Version,
};

pub type T = Transaction<u8>;

/// A register write: `addr | 0x80`, then the data, in one chip-select.
pub fn w(address: u8, data: &[u8]) -> Vec<T> {
    vec![
        T::transaction_start(),
        T::write(address | 0x80),
        T::write_vec(data.to_vec()),
        T::transaction_end(),
    ]
}

/// A register read of `response.len()` bytes from `address`.
pub fn r(address: u8, response: &[u8]) -> Vec<T> {
    vec![
        T::transaction_start(),
        T::write(address),
        T::read_vec(response.to_vec()),
        T::transaction_end(),
    ]
}

/// nIRQ that is always low (an event is pending whenever the driver looks).
pub struct LowIrq;
impl embedded_hal::digital::ErrorType for LowIrq {
    type Error = Infallible;
}
impl embedded_hal_async::digital::Wait for LowIrq {
    async fn wait_for_high(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    async fn wait_for_low(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    async fn wait_for_rising_edge(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    async fn wait_for_falling_edge(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    async fn wait_for_any_edge(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

/// nIRQ that never goes low.
pub struct QuietIrq;
impl embedded_hal::digital::ErrorType for QuietIrq {
    type Error = Infallible;
}
impl embedded_hal_async::digital::Wait for QuietIrq {
    async fn wait_for_high(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    async fn wait_for_low(&mut self) -> Result<(), Infallible> {
        core::future::pending().await
    }
    async fn wait_for_rising_edge(&mut self) -> Result<(), Infallible> {
        core::future::pending().await
    }
    async fn wait_for_falling_edge(&mut self) -> Result<(), Infallible> {
        core::future::pending().await
    }
    async fn wait_for_any_edge(&mut self) -> Result<(), Infallible> {
        core::future::pending().await
    }
}

/// Short delays complete at once; delays longer than `limit_us` (the operation deadlines)
/// never do, unless `limit_us` is `u32::MAX`.
pub struct TestDelay {
    pub limit_us: u32,
}
impl embedded_hal_async::delay::DelayNs for TestDelay {
    async fn delay_ns(&mut self, ns: u32) {
        if ns / 1_000 > self.limit_us {
            core::future::pending::<()>().await;
        }
    }
}

/// Deadlines pend forever (the IRQ decides).
pub const PATIENT: TestDelay = TestDelay { limit_us: 100_000 };
/// Every delay, deadlines included, completes at once.
pub const EXPIRED: TestDelay = TestDelay { limit_us: u32::MAX };

/// Tau Labs' 57.6 kbps setup at 430 MHz, 40 kHz hop spacing, whitening, no CRC.
pub fn tau_config() -> Config {
    let packet = PacketConfig::new()
        .with_preamble(12, 6)
        .with_sync_word([0x2D, 0xD4, 0x4B, 0x59], 4)
        .with_header([1, 2, 3, 4], 4)
        .with_header_check([1, 2, 3, 4], [0xFF; 4], 0x0F, 0x0F)
        .with_crc(Crc::Off)
        .with_whitening(true);
    let mut config = Config::new(
        ModemConfig::new(57_600, 45_000),
        packet,
        Carrier::new(430_000_000),
    );
    config.channel_spacing = ChannelSpacing::from_10khz_steps(4);
    config
}

/// Reset (without SDN) of a B1 chip that is ready at the first poll.
pub fn reset_transcript() -> Vec<T> {
    [
        r(0x00, &[0x08, 0x06]),
        w(0x07, &[0x80]),
        r(0x03, &[0x00, 0x02]),
        w(0x05, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x00]),
        r(0x00, &[0x08, 0x06]),
    ]
    .concat()
}

/// Every register of `tau_config`, in the driver's order. The values are Tau Labs'
/// `rfm22_init` sequence and its 57.6 kbps data-rate table column
/// (`flight/PiOS/Common/pios_rfm22b.c`), so this also checks that the driver can program a Tau
/// Labs-identical chip.
pub fn configure_transcript() -> Vec<T> {
    [
        w(0x07, &[0x01]),
        w(0x08, &[0x00]),
        w(0x09, &[0x7F]),
        w(0x0B, &[0xD2, 0xD5, 0xDC, 0x00]),
        w(0x0F, &[0x00, 0x00]),
        w(0x12, &[0x20, 0x00]),
        w(0x27, &[0x40]),
        // Tau Labs 57600 column: 0x1C…0x25, 0x2A, 0x58, 0x69, 0x6E…0x72 (+ whitening).
        w(
            0x1C,
            &[0x95, 0x40, 0x0A, 0x03, 0x68, 0x01, 0x3A, 0x93, 0x03, 0x29],
        ),
        w(0x2A, &[0x3C]),
        w(0x58, &[0x80]),
        w(0x69, &[0x60]),
        w(0x6E, &[0x0E, 0xBF, 0x0D, 0x23, 0x48]),
        w(0x30, &[0x88]),
        w(0x32, &[0xFF, 0x46, 0x0C, 0x30]),
        w(
            0x36,
            &[
                0x2D, 0xD4, 0x4B, 0x59, 1, 2, 3, 4, 0, 1, 2, 3, 4, 0xFF, 0xFF, 0xFF, 0xFF,
            ],
        ),
        w(0x6D, &[0x0F]),
        w(0x73, &[0x00, 0x00, 0x53, 0x00, 0x00]),
        w(0x79, &[0x00, 0x04]),
        w(0x7C, &[62, 32, 32]),
    ]
    .concat()
}

pub fn init_transcript() -> Vec<T> {
    [reset_transcript(), configure_transcript()].concat()
}

pub fn ready_radio<IRQ: embedded_hal_async::digital::Wait>(
    more: Vec<T>,
    irq: IRQ,
    delay: TestDelay,
) -> Rfm22b<Mock<u8>, IRQ, NoPin, TestDelay> {
    let spi = Mock::new(&[init_transcript(), more].concat());
    let mut radio = Rfm22b::new_without_sdn(spi, irq, delay);
    let info = block_on(radio.init(tau_config())).unwrap();
    assert_eq!(info.version, Version::B1);
    radio
}

pub fn done<IRQ, D>(radio: Rfm22b<Mock<u8>, IRQ, NoPin, D>) {
    let (mut spi, ..) = radio.release();
    spi.done();
}

/// nIRQ whose level the test sets.
pub struct SwitchIrq(pub std::rc::Rc<std::cell::Cell<bool>>);
impl embedded_hal::digital::ErrorType for SwitchIrq {
    type Error = Infallible;
}
impl embedded_hal_async::digital::Wait for SwitchIrq {
    async fn wait_for_high(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    async fn wait_for_low(&mut self) -> Result<(), Infallible> {
        if !self.0.get() {
            core::future::pending::<()>().await;
        }
        Ok(())
    }
    async fn wait_for_rising_edge(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    async fn wait_for_falling_edge(&mut self) -> Result<(), Infallible> {
        self.wait_for_low().await
    }
    async fn wait_for_any_edge(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

/// nIRQ following a script: each wait takes the next entry; `true` = low at once, `false`
/// (or an empty script) = never low.
pub struct ScriptIrq(pub std::collections::VecDeque<bool>);
impl embedded_hal::digital::ErrorType for ScriptIrq {
    type Error = Infallible;
}
impl embedded_hal_async::digital::Wait for ScriptIrq {
    async fn wait_for_high(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    async fn wait_for_low(&mut self) -> Result<(), Infallible> {
        if !self.0.pop_front().unwrap_or(false) {
            core::future::pending::<()>().await;
        }
        Ok(())
    }
    async fn wait_for_rising_edge(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    async fn wait_for_falling_edge(&mut self) -> Result<(), Infallible> {
        self.wait_for_low().await
    }
    async fn wait_for_any_edge(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}
