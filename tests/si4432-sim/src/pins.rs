//! The embedded-hal endpoints of one virtual chip: SPI, nIRQ, SDN and a virtual-time delay.
//!
//! An SPI transaction first spends its bus time (bytes × 8 at the radio's SPI clock plus a
//! fixed overhead: the async one sleeps so other tasks run, the blocking one busy-waits),
//! then acts on the chip at once, or fails with [`SpiError`] when a bus error was injected.
//! nIRQ is level-low: it is low while any enabled interrupt status bit is set and goes high
//! only when 0x03/0x04 are read. A wait for it low completes at once if the line is already
//! low, else the interrupt latency after the falling edge; a dropped wait leaves at most a
//! stale waker behind, which costs one spurious poll.

use core::convert::Infallible;
use core::future::Future;
use core::pin::Pin;
use core::task::{Context, Poll};
use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::spi::Operation;

use crate::chip::Power;
use crate::world::World;
use sim_exec::Sleep;

/// SPI bus to one chip: blocking `embedded_hal::spi::SpiDevice` and async
/// `embedded_hal_async::spi::SpiDevice`. The first byte of a transaction is the address
/// (bit 7 = write); bursts auto-increment except at the FIFO register 0x7F.
#[derive(Clone)]
pub struct SimSpi {
    world: Rc<RefCell<World>>,
    index: usize,
}

impl SimSpi {
    pub(crate) fn new(world: Rc<RefCell<World>>, index: usize) -> Self {
        Self { world, index }
    }
}

/// An SPI transaction failed (injected with `ChipHandle::fail_spi_transactions` or
/// `ChipHandle::set_spi_error_rate`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpiError;

impl embedded_hal::spi::Error for SpiError {
    fn kind(&self) -> embedded_hal::spi::ErrorKind {
        embedded_hal::spi::ErrorKind::Other
    }
}

impl embedded_hal::spi::ErrorType for SimSpi {
    type Error = SpiError;
}

impl embedded_hal::spi::SpiDevice for SimSpi {
    /// Busy-waits the bus time (the whole simulation advances, no task runs), then acts.
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), SpiError> {
        let mut world = self.world.borrow_mut();
        let cost = world.spi_cost_ns(self.index, operations);
        let until = world.now_ns().saturating_add(cost);
        world.advance_to(until);
        world.spi_transaction(self.index, operations, cost)
    }
}

impl embedded_hal_async::spi::SpiDevice for SimSpi {
    /// Sleeps the bus time (other tasks run, as with DMA), then acts.
    async fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), SpiError> {
        let (cost, deadline_ns) = {
            let world = self.world.borrow();
            let cost = world.spi_cost_ns(self.index, operations);
            (cost, world.now_ns().saturating_add(cost))
        };
        if cost > 0 {
            let sleep = self.world.borrow().time.sleep_until_ns(deadline_ns);
            sleep.await;
        }
        self.world
            .borrow_mut()
            .spi_transaction(self.index, operations, cost)
    }
}

/// The nIRQ output of one chip: `InputPin` (level) and async `Wait`.
#[derive(Clone)]
pub struct SimIrq {
    world: Rc<RefCell<World>>,
    index: usize,
}

impl SimIrq {
    pub(crate) fn new(world: Rc<RefCell<World>>, index: usize) -> Self {
        Self { world, index }
    }

    fn low(&self) -> bool {
        self.world
            .borrow()
            .radios
            .get(self.index)
            .is_some_and(|r| r.irq.low)
    }

    fn edges(&self) -> (u64, u64) {
        self.world
            .borrow()
            .radios
            .get(self.index)
            .map_or((0, 0), |r| (r.irq.falling_edges, r.irq.rising_edges))
    }

    fn wait(&self, condition: Condition) -> IrqWait {
        let (falling, rising) = self.edges();
        IrqWait {
            world: self.world.clone(),
            index: self.index,
            condition,
            falling,
            rising,
            low_at_start: self.low(),
        }
    }
}

impl embedded_hal::digital::ErrorType for SimIrq {
    type Error = Infallible;
}

impl embedded_hal::digital::InputPin for SimIrq {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(!self.low())
    }

    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(self.low())
    }
}

impl embedded_hal_async::digital::Wait for SimIrq {
    async fn wait_for_high(&mut self) -> Result<(), Infallible> {
        self.wait(Condition::High).await;
        Ok(())
    }

    async fn wait_for_low(&mut self) -> Result<(), Infallible> {
        self.wait(Condition::Low).await;
        Ok(())
    }

    async fn wait_for_rising_edge(&mut self) -> Result<(), Infallible> {
        self.wait(Condition::Rising).await;
        Ok(())
    }

    async fn wait_for_falling_edge(&mut self) -> Result<(), Infallible> {
        self.wait(Condition::Falling).await;
        Ok(())
    }

    async fn wait_for_any_edge(&mut self) -> Result<(), Infallible> {
        self.wait(Condition::AnyEdge).await;
        Ok(())
    }
}

#[derive(Clone, Copy, Debug)]
enum Condition {
    High,
    Low,
    Rising,
    Falling,
    AnyEdge,
}

/// Future of one nIRQ wait; edge counts are those seen when the wait began.
struct IrqWait {
    world: Rc<RefCell<World>>,
    index: usize,
    condition: Condition,
    falling: u64,
    rising: u64,
    /// The line was low when the wait began: a level wait for low returns at once.
    low_at_start: bool,
}

impl Future for IrqWait {
    type Output = ();

    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<()> {
        let mut world = self.world.borrow_mut();
        let now = world.now_ns();
        let Some(radio) = world.radios.get_mut(self.index) else {
            return Poll::Ready(());
        };
        // A falling edge since the wait began reaches the task only after the latency.
        let woken_at = radio
            .irq
            .fell_at_ns
            .saturating_add(radio.config.irq_latency_ns);
        let fell = radio.irq.falling_edges > self.falling;
        let line = &mut radio.irq;
        let done = match self.condition {
            Condition::High => !line.low,
            Condition::Low => self.low_at_start || (fell && now >= woken_at),
            Condition::Rising => line.rising_edges > self.rising,
            Condition::Falling => fell && now >= woken_at,
            Condition::AnyEdge => line.rising_edges > self.rising || (fell && now >= woken_at),
        };
        if done {
            return Poll::Ready(());
        }
        if fell && matches!(self.condition, Condition::Low | Condition::Falling) {
            world.add_timer(woken_at, cx.waker().clone());
            return Poll::Pending;
        }
        let Some(line) = world.radios.get_mut(self.index).map(|r| &mut r.irq) else {
            return Poll::Ready(());
        };
        if !line.waiters.iter().any(|w| w.will_wake(cx.waker())) {
            line.waiters.push(cx.waker().clone());
        }
        Poll::Pending
    }
}

/// The SDN (shutdown) input of one chip: high = shutdown, low = running. Releasing it from
/// shutdown starts a power-on reset (`ipor`, then `ichiprdy`).
#[derive(Clone)]
pub struct SimSdn {
    world: Rc<RefCell<World>>,
    index: usize,
}

impl SimSdn {
    pub(crate) fn new(world: Rc<RefCell<World>>, index: usize) -> Self {
        Self { world, index }
    }
}

impl embedded_hal::digital::ErrorType for SimSdn {
    type Error = Infallible;
}

impl embedded_hal::digital::OutputPin for SimSdn {
    fn set_high(&mut self) -> Result<(), Infallible> {
        let mut world = self.world.borrow_mut();
        world.process_due();
        world.with_chip(self.index, |chip, now, ctx| {
            if chip.power != Power::Off {
                chip.shut_down(now, ctx);
            }
        });
        world.update_irq(self.index);
        Ok(())
    }

    fn set_low(&mut self) -> Result<(), Infallible> {
        let mut world = self.world.borrow_mut();
        world.process_due();
        world.with_chip(self.index, |chip, now, ctx| {
            if chip.power == Power::Off {
                chip.power_on_reset(now, ctx);
            }
        });
        world.update_irq(self.index);
        Ok(())
    }
}

/// Virtual-time delay. Blocking `DelayNs` advances the whole simulation (every chip and the
/// medium) by the delay without running other tasks, like a busy-wait on a real MCU; async
/// `DelayNs` sleeps until virtual time reaches the deadline while other tasks run.
#[derive(Clone)]
pub struct SimDelay {
    world: Rc<RefCell<World>>,
}

impl SimDelay {
    pub(crate) fn new(world: Rc<RefCell<World>>) -> Self {
        Self { world }
    }

    fn block_for_ns(&mut self, ns: u64) {
        let mut world = self.world.borrow_mut();
        let until = world.now_ns().saturating_add(ns);
        world.advance_to(until);
    }

    /// Sleep for `ns` nanoseconds of virtual time (async).
    pub fn sleep_ns(&self, ns: u64) -> Sleep {
        self.world.borrow().time.sleep_ns(ns)
    }
}

impl embedded_hal::delay::DelayNs for SimDelay {
    fn delay_ns(&mut self, ns: u32) {
        self.block_for_ns(u64::from(ns));
    }

    fn delay_us(&mut self, us: u32) {
        self.block_for_ns(u64::from(us) * 1_000);
    }

    fn delay_ms(&mut self, ms: u32) {
        self.block_for_ns(u64::from(ms) * 1_000_000);
    }
}

impl embedded_hal_async::delay::DelayNs for SimDelay {
    async fn delay_ns(&mut self, ns: u32) {
        self.sleep_ns(u64::from(ns)).await;
    }

    async fn delay_us(&mut self, us: u32) {
        self.sleep_ns(u64::from(us) * 1_000).await;
    }

    async fn delay_ms(&mut self, ms: u32) {
        self.sleep_ns(u64::from(ms) * 1_000_000).await;
    }
}

impl core::fmt::Debug for SimSpi {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SimSpi")
            .field("radio", &self.index)
            .finish()
    }
}

impl core::fmt::Debug for SimIrq {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SimIrq")
            .field("radio", &self.index)
            .finish()
    }
}

impl core::fmt::Debug for SimSdn {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SimSdn")
            .field("radio", &self.index)
            .finish()
    }
}

impl core::fmt::Debug for SimDelay {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SimDelay").finish_non_exhaustive()
    }
}
