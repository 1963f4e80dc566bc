//! The MPU9250's SPI device with two clock rates: the datasheet (SPI interface) allows 1 MHz
//! for the configuration registers but 20 MHz for reading sensor and interrupt registers.
//! The driver configures the chip once through the slow clock; the IMU task then flips
//! [`IMU_SPI_FAST`] and every later transaction runs fast — the 23-byte burst drops from
//! 0.28 ms to 18 µs. `AliveDelay` is the driver's delay during (re-)probing: it marks the
//! loop alive for the watchdog around each wait.

use core::sync::atomic::{AtomicBool, Ordering};

use embassy_stm32::gpio::Output;
use embassy_stm32::mode::Async;
use embassy_stm32::spi::{self, Spi};
use embassy_stm32::time::Hertz;
use embassy_time::Timer;
use embedded_hal::spi::{ErrorType, Operation};
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::spi::SpiDevice;
use embedded_hal_bus::spi::{ExclusiveDevice, NoDelay};

use super::board::{IMU_SPI_FAST_HZ, IMU_SPI_SLOW_HZ};
use super::shared::loop_alive;

/// Set once the chip is configured: sensor reads may use the fast clock.
pub static IMU_SPI_FAST: AtomicBool = AtomicBool::new(false);

type Device = ExclusiveDevice<Spi<'static, Async, spi::mode::Master>, Output<'static>, NoDelay>;

/// The device, switching the bus clock between transactions when asked to.
pub struct ImuBus {
    device: Device,
    fast: bool,
}

impl ImuBus {
    /// Wraps the device (the bus must start at the slow clock).
    pub fn new(device: Device) -> Self {
        Self {
            device,
            fast: false,
        }
    }

    fn apply_speed(&mut self) {
        let fast = IMU_SPI_FAST.load(Ordering::Relaxed);
        if fast == self.fast {
            return;
        }
        let mut config = spi::Config::default();
        config.mode = spi::MODE_3;
        config.frequency = Hertz(if fast {
            IMU_SPI_FAST_HZ
        } else {
            IMU_SPI_SLOW_HZ
        });
        // set_config only fails for an impossible frequency; then the bus stays slow.
        if self.device.bus_mut().set_config(&config).is_ok() {
            self.fast = fast;
        }
    }
}

impl ErrorType for ImuBus {
    type Error = <Device as ErrorType>::Error;
}

impl SpiDevice for ImuBus {
    async fn transaction(
        &mut self,
        operations: &mut [Operation<'_, u8>],
    ) -> Result<(), Self::Error> {
        self.apply_speed();
        self.device.transaction(operations).await
    }
}

/// The driver's waits (a 100 ms reset) keep the loop counted alive (`shared::loop_alive`:
/// the loop cannot take the app's lock), so a re-probe never starves the watchdog.
pub struct AliveDelay;

impl DelayNs for AliveDelay {
    async fn delay_ns(&mut self, ns: u32) {
        loop_alive();
        Timer::after_nanos(u64::from(ns)).await;
        loop_alive();
    }
}
