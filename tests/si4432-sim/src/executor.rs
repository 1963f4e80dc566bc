//! Deterministic single-threaded async execution in virtual time.
//!
//! `Simulation` polls every woken task (in spawn order) until all are pending, then moves
//! the virtual clock to the next scheduled thing — a timer, a chip settling, a byte on air —
//! and wakes whatever depends on it. No threads, no wall clock: the same seed and the same
//! tasks give the same trace, and idle time costs nothing.

use core::future::Future;
use core::pin::Pin;
use core::sync::atomic::{AtomicBool, Ordering};
use core::task::{Context, Waker};
use core::time::Duration;
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::{Arc, Mutex};
use std::task::Wake;

use crate::medium::{Medium, MediumConfig};
use crate::pins::SimDelay;
use crate::world::World;

type BoxedTask = Pin<Box<dyn Future<Output = ()>>>;

/// Indices of tasks to poll.
#[derive(Debug, Default)]
struct ReadyQueue {
    queue: Mutex<Vec<usize>>,
}

#[derive(Debug)]
struct TaskWaker {
    index: usize,
    scheduled: AtomicBool,
    ready: Arc<ReadyQueue>,
}

impl Wake for TaskWaker {
    fn wake(self: Arc<Self>) {
        self.wake_by_ref();
    }

    fn wake_by_ref(self: &Arc<Self>) {
        if !self.scheduled.swap(true, Ordering::AcqRel)
            && let Ok(mut queue) = self.ready.queue.lock()
        {
            queue.push(self.index);
        }
    }
}

struct Slot {
    future: Option<BoxedTask>,
    waker: Arc<TaskWaker>,
}

/// What a task shares with its `Task` handle.
struct TaskState<T> {
    result: RefCell<Option<T>>,
    finished: core::cell::Cell<bool>,
    joiner: RefCell<Option<Waker>>,
}

/// Handle to a spawned task's result. Also a future: awaiting it (from another task)
/// yields the output once the task finishes.
pub struct Task<T> {
    state: Rc<TaskState<T>>,
}

impl<T> core::fmt::Debug for Task<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Task")
            .field("finished", &self.is_finished())
            .finish()
    }
}

impl<T> Task<T> {
    /// True once the task has run to completion.
    pub fn is_finished(&self) -> bool {
        self.state.finished.get()
    }

    /// The task's output, once (None before it finishes or after it was taken).
    pub fn take(&self) -> Option<T> {
        self.state.result.borrow_mut().take()
    }
}

impl<T> Future for Task<T> {
    type Output = T;

    /// Ready with the output when the task has finished; pends forever if the output was
    /// already taken.
    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> core::task::Poll<T> {
        if let Some(value) = self.take() {
            return core::task::Poll::Ready(value);
        }
        *self.state.joiner.borrow_mut() = Some(cx.waker().clone());
        core::task::Poll::Pending
    }
}

/// Spawns tasks into a simulation from anywhere, including from inside a task.
#[derive(Clone)]
pub struct Spawner {
    tasks: Rc<RefCell<Vec<Slot>>>,
    ready: Arc<ReadyQueue>,
}

impl core::fmt::Debug for Spawner {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Spawner").finish_non_exhaustive()
    }
}

impl Spawner {
    /// Add a task; it first runs the next time the simulation polls.
    pub fn spawn<F>(&self, future: F) -> Task<F::Output>
    where
        F: Future + 'static,
    {
        let state = Rc::new(TaskState {
            result: RefCell::new(None),
            finished: core::cell::Cell::new(false),
            joiner: RefCell::new(None),
        });
        let shared = state.clone();
        let wrapped = async move {
            let value = future.await;
            *shared.result.borrow_mut() = Some(value);
            shared.finished.set(true);
            if let Some(joiner) = shared.joiner.borrow_mut().take() {
                joiner.wake();
            }
        };
        let mut tasks = self.tasks.borrow_mut();
        let waker = Arc::new(TaskWaker {
            index: tasks.len(),
            scheduled: AtomicBool::new(false),
            ready: self.ready.clone(),
        });
        waker.wake_by_ref();
        tasks.push(Slot {
            future: Some(Box::pin(wrapped)),
            waker,
        });
        Task { state }
    }
}

/// A whole simulation: virtual clock, RF medium, radios and the tasks that drive them.
pub struct Simulation {
    world: Rc<RefCell<World>>,
    tasks: Rc<RefCell<Vec<Slot>>>,
    ready: Arc<ReadyQueue>,
}

impl core::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Simulation")
            .field("now", &self.now())
            .field("tasks", &self.tasks.borrow().len())
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
        Self {
            world: Rc::new(RefCell::new(World::new(seed, config))),
            tasks: Rc::new(RefCell::new(Vec::new())),
            ready: Arc::new(ReadyQueue::default()),
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

    /// Current virtual time.
    pub fn now(&self) -> Duration {
        Duration::from_nanos(self.world.borrow().now_ns)
    }

    /// Add a task; it first runs at the next `run_*` call.
    pub fn spawn<F>(&self, future: F) -> Task<F::Output>
    where
        F: Future + 'static,
    {
        self.spawner().spawn(future)
    }

    /// A handle that spawns into this simulation (usable inside tasks).
    pub fn spawner(&self) -> Spawner {
        Spawner {
            tasks: self.tasks.clone(),
            ready: self.ready.clone(),
        }
    }

    /// Run for `duration` of virtual time.
    pub fn run_for(&self, duration: Duration) {
        let deadline = self
            .world
            .borrow()
            .now_ns
            .saturating_add(duration_ns(duration));
        self.drive(deadline, || false);
    }

    /// Run until `condition` holds (checked whenever every task is idle) or nothing is left
    /// to happen. Returns whether the condition held. Loops forever if tasks keep time
    /// moving and the condition never holds; prefer `run_until_or` in tests.
    pub fn run_until(&self, condition: impl FnMut() -> bool) -> bool {
        self.drive(u64::MAX, condition)
    }

    /// Like `run_until`, but gives up after `limit` of virtual time.
    pub fn run_until_or(&self, limit: Duration, condition: impl FnMut() -> bool) -> bool {
        let deadline = self
            .world
            .borrow()
            .now_ns
            .saturating_add(duration_ns(limit));
        self.drive(deadline, condition)
    }

    fn drive(&self, deadline_ns: u64, mut stop: impl FnMut() -> bool) -> bool {
        loop {
            self.poll_ready();
            if stop() {
                return true;
            }
            let next = self.world.borrow().next_event_ns();
            match next {
                Some(t) if t <= deadline_ns => self.world.borrow_mut().advance_one(t),
                _ => {
                    if deadline_ns != u64::MAX {
                        self.world.borrow_mut().advance_to(deadline_ns);
                    }
                    self.poll_ready();
                    return stop();
                }
            }
        }
    }

    /// Poll woken tasks until none is woken.
    fn poll_ready(&self) {
        loop {
            let batch = match self.ready.queue.lock() {
                Ok(mut queue) => core::mem::take(&mut *queue),
                Err(_) => return,
            };
            if batch.is_empty() {
                return;
            }
            for index in batch {
                let taken = self.tasks.borrow_mut().get_mut(index).map(|slot| {
                    slot.waker.scheduled.store(false, Ordering::Release);
                    (slot.future.take(), slot.waker.clone())
                });
                let Some((Some(mut future), waker)) = taken else {
                    continue;
                };
                let waker = Waker::from(waker);
                let mut cx = Context::from_waker(&waker);
                if future.as_mut().poll(&mut cx).is_pending()
                    && let Some(slot) = self.tasks.borrow_mut().get_mut(index)
                {
                    slot.future = Some(future);
                }
            }
        }
    }
}

fn duration_ns(d: Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tasks_interleave_in_virtual_time_and_idle_time_is_skipped() {
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

    #[test]
    fn run_until_reports_a_condition_that_can_no_longer_become_true() {
        let sim = Simulation::new(0);
        let delay = sim.delay();
        let task = sim.spawn(async move {
            delay.sleep_ns(1_000).await;
            7
        });
        assert!(!sim.run_until(|| false));
        assert_eq!(sim.now(), Duration::from_micros(1));
        assert!(task.is_finished());
        assert_eq!(task.take(), Some(7));
        assert_eq!(task.take(), None);
        assert!(sim.run_until_or(Duration::from_millis(1), || true));
    }
}
