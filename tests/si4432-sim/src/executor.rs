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
