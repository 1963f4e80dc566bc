//! The chip-level world on the simulators' one executor (`sim_exec::Executor`): the medium's
//! chips are the executor's [`sim_exec::Events`], so it polls every woken task (in wake
//! order) until all are pending, then moves virtual time to the next scheduled thing — a
//! timer, a chip settling, a byte on air — and wakes whatever depends on it. No threads, no
//! wall clock: the same seed and the same tasks give the same trace, and idle time costs
//! nothing.

use core::future::Future;
use core::time::Duration;
use std::cell::RefCell;
use std::rc::Rc;

use sim_exec::{Executor, Task, VirtualTime};

use crate::medium::{Medium, MediumConfig};
use crate::pins::SimDelay;
use crate::world::World;

/// Spawns tasks into a simulation from anywhere, including from inside a task.
pub type Spawner = sim_exec::Spawner<'static>;

/// A whole simulation: virtual clock, RF medium, radios and the tasks that drive them.
pub struct Simulation {
    world: Rc<RefCell<World>>,
    executor: Executor<'static>,
}

impl core::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Simulation")
            .field("now", &self.now())
            .field("executor", &self.executor)
            .finish()
    }
}

impl Simulation {
    /// A simulation whose randomness is fixed by `seed`, with a default medium.
    pub fn new(seed: u64) -> Self {
        Self::with_config(seed, MediumConfig::default())
    }

    /// A simulation with a configured medium.
    pub fn with_config(seed: u64, config: MediumConfig) -> Self {
        let time = VirtualTime::new();
        let world = Rc::new(RefCell::new(World::new(seed, config, time.clone())));
        Self {
            executor: Executor::with_events(time, world.clone()),
            world,
        }
    }

    /// The RF medium (add radios, inject interference, read the trace).
    pub fn medium(&self) -> Medium {
        Medium {
            world: self.world.clone(),
        }
    }

    /// A virtual-time delay not tied to any radio.
    pub fn delay(&self) -> SimDelay {
        SimDelay::new(self.world.clone())
    }

    /// The virtual time the chips and tasks share (for a board's [`crate::SimClock`]).
    pub fn time(&self) -> VirtualTime {
        self.executor.time().clone()
    }

    /// Current virtual time.
    pub fn now(&self) -> Duration {
        self.executor.time().now()
    }

    /// Add a task; it first runs at the next `run_*` call.
    pub fn spawn<F>(&self, future: F) -> Task<F::Output>
    where
        F: Future + 'static,
    {
        self.executor.spawn(future)
    }

    /// A handle that spawns into this simulation (usable inside tasks).
    pub fn spawner(&self) -> Spawner {
        self.executor.spawner()
    }

    /// Run for `duration` of virtual time.
    pub fn run_for(&self, duration: Duration) {
        self.executor.run_for(duration);
    }

    /// Run until `condition` holds (checked whenever every task is idle) or nothing is left
    /// to happen. Returns whether the condition held. Loops forever if tasks keep time
    /// moving and the condition never holds; prefer `run_until_or` in tests.
    pub fn run_until(&self, condition: impl FnMut() -> bool) -> bool {
        self.executor.run_until(condition)
    }

    /// Like `run_until`, but gives up after `limit` of virtual time.
    pub fn run_until_or(&self, limit: Duration, condition: impl FnMut() -> bool) -> bool {
        self.executor.run_until_or(limit, condition)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tasks_sleep_on_the_chips_time_and_idle_time_is_skipped() {
        let sim = Simulation::new(0);
        let log = Rc::new(RefCell::new(Vec::new()));
        for (name, period_us) in [("a", 300u64), ("b", 500)] {
            let delay = sim.delay();
            let medium = sim.medium();
            let log = log.clone();
            sim.spawn(async move {
                for _ in 0..3 {
                    delay.sleep_ns(period_us * 1_000).await;
                    log.borrow_mut().push((name, medium.now().as_micros()));
                }
            });
        }
        sim.run_for(Duration::from_secs(3600));
        assert_eq!(sim.now(), Duration::from_secs(3600));
        assert_eq!(sim.medium().time().now(), sim.now());
        assert_eq!(
            *log.borrow(),
            vec![
                ("a", 300),
                ("b", 500),
                ("a", 600),
                ("a", 900),
                ("b", 1000),
                ("b", 1500)
            ]
        );
    }

    #[test]
    fn tasks_spawned_inside_tasks_can_be_awaited() {
        let sim = Simulation::new(0);
        let spawner = sim.spawner();
        let delay = sim.delay();
        let outer = sim.spawn(async move {
            let inner = spawner.spawn(async move {
                delay.sleep_ns(2_500).await;
                21
            });
            inner.await * 2
        });
        assert!(sim.run_until_or(Duration::from_millis(1), || outer.is_finished()));
        assert_eq!(outer.take(), Some(42));
        assert_eq!(sim.now(), Duration::from_nanos(2_500));
    }
}
