//! SPI transcript tests (embedded-hal-mock): the exact register traffic of init, TX and RX,
//! including packets longer than the FIFO, CRC errors, timeouts, a power-on reset in the
//! middle of RX and an unplugged chip. Expected bytes are written out from the datasheet and
//! radio.md, not computed with the driver's own functions.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)] // test code

use core::convert::Infallible;

use embassy_futures::block_on;
use embedded_hal_mock::eh1::spi::{Mock, Transaction};
use radio_rfm22b::{
    Carrier, ChannelSpacing, Config, Crc, Error, ModemConfig, NoPin, PacketConfig, Rfm22b,
    RxOutcome, Version,
};

type T = Transaction<u8>;

/// A register write: `addr | 0x80`, then the data, in one chip-select.
fn w(address: u8, data: &[u8]) -> Vec<T> {
    vec![
        T::transaction_start(),
        T::write(address | 0x80),
        T::write_vec(data.to_vec()),
        T::transaction_end(),
    ]
}

/// A register read of `response.len()` bytes from `address`.
fn r(address: u8, response: &[u8]) -> Vec<T> {
    vec![
        T::transaction_start(),
        T::write(address),
        T::read_vec(response.to_vec()),
        T::transaction_end(),
    ]
}

/// nIRQ that is always low (an event is pending whenever the driver looks).
struct LowIrq;
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
struct QuietIrq;
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
struct TestDelay {
    limit_us: u32,
}
impl embedded_hal_async::delay::DelayNs for TestDelay {
    async fn delay_ns(&mut self, ns: u32) {
        if ns / 1_000 > self.limit_us {
            core::future::pending::<()>().await;
        }
    }
}

/// Deadlines pend forever (the IRQ decides).
const PATIENT: TestDelay = TestDelay { limit_us: 100_000 };
/// Every delay, deadlines included, completes at once.
const EXPIRED: TestDelay = TestDelay { limit_us: u32::MAX };

/// Tau Labs' 57.6 kbps setup at 430 MHz, 40 kHz hop spacing, whitening, no CRC.
fn tau_config() -> Config {
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
fn reset_transcript() -> Vec<T> {
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

/// Every register of `tau_config`, in the driver's order.
fn configure_transcript() -> Vec<T> {
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

fn init_transcript() -> Vec<T> {
    [reset_transcript(), configure_transcript()].concat()
}

fn ready_radio<IRQ: embedded_hal_async::digital::Wait>(
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

fn done<IRQ, D>(radio: Rfm22b<Mock<u8>, IRQ, NoPin, D>) {
    let (mut spi, ..) = radio.release();
    spi.done();
}

#[test]
fn init_writes_the_whole_configuration() {
    let radio = ready_radio(vec![], LowIrq, PATIENT);
    done(radio);
}

#[test]
fn sdn_pulse_precedes_the_reset() {
    use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as PinT};
    let sdn = PinMock::new(&[PinT::set(State::High), PinT::set(State::Low)]);
    let spi = Mock::new(&reset_transcript());
    let mut radio = Rfm22b::new(spi, LowIrq, sdn, PATIENT);
    block_on(radio.reset()).unwrap();
    let (mut spi, _, mut sdn, _) = radio.release();
    spi.done();
    sdn.done();
}

#[test]
fn unplugged_chip_is_not_an_si4432() {
    for floating in [0x00, 0xFF] {
        let spi = Mock::new(&r(0x00, &[floating, floating]));
        let mut radio = Rfm22b::new_without_sdn(spi, LowIrq, PATIENT);
        let err = block_on(radio.init(tau_config())).unwrap_err();
        assert_eq!(
            err,
            Error::NotAnSi4432 {
                device_type: floating,
                version: floating
            }
        );
        done(radio);
    }
}

#[test]
fn chip_that_never_gets_ready_times_out() {
    let mut t = [r(0x00, &[0x08, 0x04]), w(0x07, &[0x80])].concat();
    for _ in 0..50 {
        t.extend(r(0x03, &[0x00, 0x00]));
    }
    let spi = Mock::new(&t);
    let mut radio = Rfm22b::new_without_sdn(spi, LowIrq, PATIENT);
    assert_eq!(block_on(radio.init(tau_config())), Err(Error::Timeout));
    done(radio);
}

#[test]
fn transmit_short_packet() {
    let t = [
        w(0x08, &[0x01]),
        w(0x08, &[0x00]),
        w(0x3E, &[3]),
        w(0x7F, &[0x00, 0x11, 0x22]),
        w(0x05, &[0x84, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x09]),
        r(0x03, &[0x04, 0x00]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    block_on(radio.transmit(&[0x00, 0x11, 0x22], 10_000_000)).unwrap();
    done(radio);
}

#[test]
fn transmit_long_packet_refills_the_fifo() {
    let data: Vec<u8> = (0..100).collect();
    let t = [
        w(0x08, &[0x01]),
        w(0x08, &[0x00]),
        w(0x3E, &[100]),
        w(0x7F, &data[..64]),
        w(0x05, &[0xA4, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x09]),
        r(0x03, &[0x20, 0x00]),
        w(0x7F, &data[64..95]),
        r(0x03, &[0x20, 0x00]),
        w(0x7F, &data[95..]),
        w(0x05, &[0x84]),
        r(0x03, &[0x04, 0x00]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    block_on(radio.transmit(&data, 10_000_000)).unwrap();
    done(radio);
}

#[test]
fn transmit_rejects_bad_lengths_without_bus_traffic() {
    let mut radio = ready_radio(vec![], LowIrq, PATIENT);
    assert_eq!(
        block_on(radio.transmit(&[], 1_000)),
        Err(Error::InvalidLength { len: 0 })
    );
    assert_eq!(
        block_on(radio.transmit(&[0; 256], 1_000)),
        Err(Error::InvalidLength { len: 256 })
    );
    done(radio);
}

#[test]
fn transmit_timeout_on_a_vanished_chip_reports_it() {
    let t = [
        w(0x08, &[0x01]),
        w(0x08, &[0x00]),
        w(0x3E, &[1]),
        w(0x7F, &[0xAA]),
        w(0x05, &[0x84, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x09]),
        // Deadline: idle, interrupts off, clear status, flush TX, probe.
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x08, &[0x01]),
        w(0x08, &[0x00]),
        r(0x00, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, QuietIrq, EXPIRED);
    assert_eq!(
        block_on(radio.transmit(&[0xAA], 1_000)),
        Err(Error::NotAnSi4432 {
            device_type: 0,
            version: 0
        })
    );
    done(radio);
}

fn rx_start() -> Vec<T> {
    [
        w(0x08, &[0x02]),
        w(0x08, &[0x00]),
        w(0x05, &[0x93, 0x80]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x05]),
    ]
    .concat()
}

#[test]
fn receive_short_packet_with_rssi_and_afc() {
    let payload = [9, 8, 7, 6, 5];
    let t = [
        rx_start(),
        r(0x03, &[0x00, 0x80]),
        r(0x26, &[100]),
        r(0x2B, &[0x02, 0x40]),
        r(0x03, &[0x02, 0x00]),
        r(0x47, &[1, 2, 3, 4, 5]),
        r(0x7F, &payload),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 64];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    let RxOutcome::Packet(p) = outcome else {
        panic!("{outcome:?}")
    };
    assert_eq!(p.len, 5);
    assert_eq!(buf[..5], payload);
    assert_eq!(p.header, [1, 2, 3, 4]);
    // raw 100 → 50 − 122 dBm; afc_corr = 0b00_0000_1001 = 9 steps of 156.25 Hz.
    assert_eq!(p.signal.rssi_dbm, -72);
    assert_eq!(p.signal.rssi_raw, 100);
    assert_eq!(p.signal.afc_offset_hz, 1_406);
    done(radio);
}

#[test]
fn receive_long_packet_drains_the_fifo() {
    let payload: Vec<u8> = (0..100).map(|i| 255 - i).collect();
    let head = [0xDE, 0xAD, 0xBE, 0xEF, 100];
    let t = [
        rx_start(),
        r(0x03, &[0x10, 0x80]),
        r(0x26, &[90]),
        r(0x2B, &[0xFF, 0xC0]),
        r(0x47, &head),
        r(0x7F, &payload[..32]),
        r(0x03, &[0x10, 0x00]),
        r(0x47, &head),
        r(0x7F, &payload[32..64]),
        r(0x03, &[0x10, 0x00]),
        r(0x47, &head),
        r(0x7F, &payload[64..96]),
        r(0x03, &[0x02, 0x00]),
        r(0x47, &head),
        r(0x7F, &payload[96..]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 255];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    let RxOutcome::Packet(p) = outcome else {
        panic!("{outcome:?}")
    };
    assert_eq!(p.len, 100);
    assert_eq!(buf[..100], payload[..]);
    assert_eq!(p.header, [0xDE, 0xAD, 0xBE, 0xEF]);
    assert_eq!(p.signal.rssi_dbm, -77);
    assert_eq!(p.signal.afc_offset_hz, -156);
    done(radio);
}

fn discard_tail() -> Vec<T> {
    [
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x08, &[0x02]),
        w(0x08, &[0x00]),
    ]
    .concat()
}

#[test]
fn receive_crc_error_is_an_outcome_and_flushes() {
    let t = [
        rx_start(),
        r(0x03, &[0x01, 0x80]),
        r(0x26, &[60]),
        r(0x2B, &[0x00, 0x00]),
        discard_tail(),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 64];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    let RxOutcome::CrcError(signal) = outcome else {
        panic!("{outcome:?}")
    };
    assert_eq!(signal.rssi_dbm, -92);
    done(radio);
}

#[test]
fn receive_too_long_for_the_buffer_is_discarded() {
    let t = [
        rx_start(),
        r(0x03, &[0x10, 0x00]),
        r(0x47, &[0, 0, 0, 0, 200]),
        r(0x26, &[80]),
        r(0x2B, &[0x00, 0x00]),
        discard_tail(),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 64];
    let outcome = block_on(radio.receive(&mut buf, 10_000_000)).unwrap();
    assert!(
        matches!(outcome, RxOutcome::TooLong { len: 200, .. }),
        "{outcome:?}"
    );
    done(radio);
}

#[test]
fn receive_timeout_is_an_outcome() {
    let t = [rx_start(), discard_tail(), r(0x00, &[0x08, 0x06])].concat();
    let mut radio = ready_radio(t, QuietIrq, EXPIRED);
    let mut buf = [0u8; 64];
    assert_eq!(
        block_on(radio.receive(&mut buf, 5_000)),
        Ok(RxOutcome::Timeout)
    );
    done(radio);
}

#[test]
fn power_on_reset_during_receive_reinitialises() {
    let t = [rx_start(), r(0x03, &[0x00, 0x01]), init_transcript()].concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 64];
    assert_eq!(
        block_on(radio.receive(&mut buf, 10_000_000)),
        Err(Error::ChipReset)
    );
    done(radio);
}

#[test]
fn all_ones_status_means_reset_then_not_an_si4432() {
    // A chip that drops off the bus mid-RX reads 0xFF everywhere: ipor looks set, the
    // re-init probe then fails cleanly.
    let t = [rx_start(), r(0x03, &[0xFF, 0xFF]), r(0x00, &[0xFF, 0xFF])].concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    let mut buf = [0u8; 64];
    assert_eq!(
        block_on(radio.receive(&mut buf, 10_000_000)),
        Err(Error::NotAnSi4432 {
            device_type: 0xFF,
            version: 0xFF
        })
    );
    done(radio);
}

#[test]
fn locked_module_is_detected_and_reinitialised() {
    let t = [
        r(0x00, &[0x08, 0x06]),
        r(0x0C, &[0x00]),
        init_transcript(),
        // Second check: healthy.
        r(0x00, &[0x08, 0x06]),
        r(0x0C, &[0xD5]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    assert_eq!(block_on(radio.check_health()), Err(Error::ChipReset));
    assert_eq!(block_on(radio.check_health()), Ok(()));
    done(radio);
}

#[test]
fn channel_power_rssi_temperature_sleep() {
    let t = [
        w(0x79, &[17]),
        w(0x6D, &[0x0C]),
        r(0x26, &[45]),
        w(0x0F, &[0x80]),
        r(0x0F, &[0x00]),
        r(0x0F, &[0x80]),
        r(0x11, &[178]),
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x00]),
    ]
    .concat();
    let mut radio = ready_radio(t, LowIrq, PATIENT);
    block_on(radio.set_channel(17)).unwrap();
    assert_eq!(radio.channel(), 17);
    block_on(radio.set_tx_power(radio_rfm22b::TxPower::try_from_dbm(11).unwrap())).unwrap();
    assert_eq!(block_on(radio.rssi_dbm()), Ok(-100));
    assert_eq!(block_on(radio.read_temperature_decidegrees_c()), Ok(250));
    block_on(radio.sleep()).unwrap();
    done(radio);
}

#[test]
fn dropped_receive_is_stopped_by_the_next_operation() {
    // Start RX, drop the future after it armed the chip, then transmit.
    let t = [
        rx_start(),
        // The abort before the transmit.
        w(0x07, &[0x01]),
        w(0x05, &[0x00, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x08, &[0x01]),
        w(0x08, &[0x00]),
        w(0x3E, &[1]),
        w(0x7F, &[0x55]),
        w(0x05, &[0x84, 0x00]),
        r(0x03, &[0x00, 0x00]),
        w(0x07, &[0x09]),
        r(0x03, &[0x04, 0x00]),
        w(0x05, &[0x00, 0x00]),
    ]
    .concat();
    let line_low = std::rc::Rc::new(std::cell::Cell::new(false));
    let spi = Mock::new(&[init_transcript(), t].concat());
    let mut radio = Rfm22b::new_without_sdn(spi, SwitchIrq(line_low.clone()), PATIENT);
    block_on(radio.init(tau_config())).unwrap();
    {
        let mut buf = [0u8; 8];
        let mut rx = core::pin::pin!(radio.receive(&mut buf, 10_000_000));
        let mut cx = core::task::Context::from_waker(core::task::Waker::noop());
        assert!(rx.as_mut().poll(&mut cx).is_pending());
    }
    line_low.set(true);
    block_on(radio.transmit(&[0x55], 10_000_000)).unwrap();
    done(radio);
}

/// nIRQ whose level the test sets.
struct SwitchIrq(std::rc::Rc<std::cell::Cell<bool>>);
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
