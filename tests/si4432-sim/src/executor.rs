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

/// Handle to a spawned task's result.
#[derive(Debug)]
pub struct Task<T> {
    result: Rc<RefCell<Option<T>>>,
    finished: Rc<core::cell::Cell<bool>>,
}

impl<T> Task<T> {
    /// True once the task has run to completion.
    pub fn is_finished(&self) -> bool {
        self.finished.get()
    }

    /// The task's output, once (None before it finishes or after it was taken).
    pub fn take(&self) -> Option<T> {
        self.result.borrow_mut().take()
    }
}

/// A whole simulation: virtual clock, RF medium, radios and the tasks that drive them.
pub struct Simulation {
    world: Rc<RefCell<World>>,
    tasks: RefCell<Vec<Slot>>,
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
            tasks: RefCell::new(Vec::new()),
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
        let result = Rc::new(RefCell::new(None));
        let finished = Rc::new(core::cell::Cell::new(false));
        let (r, f) = (result.clone(), finished.clone());
        let wrapped = async move {
            let value = future.await;
            *r.borrow_mut() = Some(value);
            f.set(true);
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
        Task { result, finished }
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
