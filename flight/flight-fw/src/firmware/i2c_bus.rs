//! The MS5611's I²C bus, made unable to hang the baro task.
//!
//! - [`recover`]: the bus clear of the I²C specification (NXP UM10204 §3.1.16: "If the data
//!   line (SDA) is stuck LOW, the master should send nine clock pulses", then a STOP), with
//!   SCL and SDA as open-drain GPIO, before the peripheral is (re-)initialised. An MS5611
//!   reset in the middle of a read (an MCU reset, a brown-out) keeps driving SDA low for the
//!   rest of its byte; without the clear, the F4's I2C v1 waits for its START forever.
//! - [`TimedI2c`]: every transaction under [`TRANSACTION_TIMEOUT`]; embassy-stm32's async
//!   I2C v1 has none (it waits for the START and each event). A timeout ends the transfer
//!   (the future is dropped) and the task starts over with a recovery.

use embassy_stm32::gpio::{Flex, Speed};
use embassy_time::{Duration, with_timeout};
use embedded_hal_async::i2c::{ErrorKind, ErrorType, I2c, Operation, SevenBitAddress};

/// Longest I²C transaction, far above the MS5611's (a 3-byte read at 400 kHz: 90 µs).
pub const TRANSACTION_TIMEOUT: Duration = Duration::from_millis(5);
/// Half an SCL period of the bus clear at 100 kHz, in CPU cycles at 168 MHz.
const HALF_PERIOD_CYCLES: u32 = 840;

fn half_period() {
    cortex_m::asm::delay(HALF_PERIOD_CYCLES);
}

/// Clears a bus a slave holds: SCL clocked until SDA is released (nine clocks at most), then
/// a STOP. Both pins end released (high through the board's pull-ups) as GPIO; the caller
/// hands them to the peripheral again. Returns whether SDA was released.
pub fn recover(scl: &mut Flex<'_>, sda: &mut Flex<'_>) -> bool {
    if cfg!(pil_i2c_unguarded) {
        return sda.is_high();
    }
    sda.set_high();
    sda.set_as_input_output(Speed::Low);
    scl.set_high();
    scl.set_as_input_output(Speed::Low);
    half_period();
    for _ in 0..9 {
        if sda.is_high() {
            break;
        }
        scl.set_low();
        half_period();
        scl.set_high();
        half_period();
    }
    // STOP: SDA rises while SCL is high.
    scl.set_low();
    half_period();
    sda.set_low();
    half_period();
    scl.set_high();
    half_period();
    sda.set_high();
    half_period();
    sda.is_high()
}

/// A transaction failed on the bus or took longer than [`TRANSACTION_TIMEOUT`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum TimedError<E> {
    /// The peripheral's error.
    Bus(E),
    /// No end within the timeout: the bus needs a recovery.
    Timeout,
}

impl<E: embedded_hal_async::i2c::Error> embedded_hal_async::i2c::Error for TimedError<E> {
    fn kind(&self) -> ErrorKind {
        match self {
            TimedError::Bus(e) => e.kind(),
            TimedError::Timeout => ErrorKind::Other,
        }
    }
}

/// An I²C bus whose every transaction ends within [`TRANSACTION_TIMEOUT`].
pub struct TimedI2c<B>(pub B);

impl<B: ErrorType> ErrorType for TimedI2c<B> {
    type Error = TimedError<B::Error>;
}

impl<B: I2c> I2c for TimedI2c<B> {
    async fn transaction(
        &mut self,
        address: SevenBitAddress,
        operations: &mut [Operation<'_>],
    ) -> Result<(), Self::Error> {
        if cfg!(pil_i2c_unguarded) {
            return self
                .0
                .transaction(address, operations)
                .await
                .map_err(TimedError::Bus);
        }
        match with_timeout(TRANSACTION_TIMEOUT, self.0.transaction(address, operations)).await {
            Ok(result) => result.map_err(TimedError::Bus),
            Err(_) => Err(TimedError::Timeout),
        }
    }
}
