//! The deterministic single-threaded executor: polls woken tasks in the order they were woken
//! until none is, then moves virtual time to the next wake-up or world event and repeats.
//!
//! Tasks are woken by real wakers (a sleep, a chip's nIRQ, another task finishing) or, for
//! futures that check shared state when polled instead of registering a waker (the
//! packet-level mock's radio), by a wake-up for everyone ([`VirtualTime::wake_all_at`]),
//! which polls every unfinished task in spawn order.

use core::future::Future;
use core::pin::Pin;
use core::sync::atomic::{AtomicBool, Ordering};
use core::task::{Context, Poll, Waker};
use core::time::Duration;
use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::sync::{Arc, Mutex};
use std::task::Wake;

use crate::time::{Events, NoEvents, VirtualTime};

type BoxedTask<'a> = Pin<Box<dyn Future<Output = ()> + 'a>>;

/// Indices of tasks to poll, in the order they were woken.
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

struct Slot<'a> {
    future: Option<BoxedTask<'a>>,
    /// The task has finished (its future is gone for good, not just out being polled).
    finished: bool,
    waker: Arc<TaskWaker>,
}

/// What a task shares with its `Task` handle.
struct TaskState<T> {
    result: RefCell<Option<T>>,
    finished: Cell<bool>,
    joiner: RefCell<Option<Waker>>,
}

/// Handle to a spawned task's result. Also a future: awaiting it (from another task)
/// yields the output once the task finishes. Dropping it does not stop the task.
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
    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<T> {
        if let Some(value) = self.take() {
            return Poll::Ready(value);
        }
        *self.state.joiner.borrow_mut() = Some(cx.waker().clone());
        Poll::Pending
    }
}

/// Spawns tasks into an executor from anywhere, including from inside a task.
#[derive(Clone)]
pub struct Spawner<'a> {
    tasks: Rc<RefCell<Vec<Slot<'a>>>>,
    ready: Arc<ReadyQueue>,
}

impl core::fmt::Debug for Spawner<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Spawner").finish_non_exhaustive()
    }
}

impl<'a> Spawner<'a> {
    /// Adds a task; it first runs the next time the executor polls.
    pub fn spawn<F>(&self, future: F) -> Task<F::Output>
    where
        F: Future + 'a,
        F::Output: 'a,
    {
        let state = Rc::new(TaskState {
            result: RefCell::new(None),
            finished: Cell::new(false),
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
            finished: false,
            waker,
        });
        Task { state }
    }
}

/// The executor: its tasks, the virtual time they sleep on and, optionally, a world whose
/// events also move time ([`Executor::with_events`]).
pub struct Executor<'a> {
    time: VirtualTime,
    events: Rc<RefCell<dyn Events + 'a>>,
    tasks: Rc<RefCell<Vec<Slot<'a>>>>,
    ready: Arc<ReadyQueue>,
}

impl core::fmt::Debug for Executor<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Executor")
            .field("now_ns", &self.time.now_ns())
            .field("tasks", &self.tasks.borrow().len())
            .finish()
    }
}

impl<'a> Executor<'a> {
    /// An executor on `time`.
    pub fn new(time: VirtualTime) -> Self {
        Self::with_events(time, Rc::new(RefCell::new(NoEvents)))
    }

    /// An executor on `time` that also stops at every instant `events` has something due,
    /// running those events before the wake-ups of that instant fire.
    pub fn with_events(time: VirtualTime, events: Rc<RefCell<dyn Events + 'a>>) -> Self {
        Self {
            time,
            events,
            tasks: Rc::new(RefCell::new(Vec::new())),
            ready: Arc::new(ReadyQueue::default()),
        }
    }

    /// The virtual time the tasks run on.
    pub fn time(&self) -> &VirtualTime {
        &self.time
    }

    /// Adds a task; it first runs at the next `run_*` call.
    pub fn spawn<F>(&self, future: F) -> Task<F::Output>
    where
        F: Future + 'a,
        F::Output: 'a,
    {
        self.spawner().spawn(future)
    }

    /// A handle that spawns into this executor (usable inside tasks).
    pub fn spawner(&self) -> Spawner<'a> {
        Spawner {
            tasks: self.tasks.clone(),
            ready: self.ready.clone(),
        }
    }

    /// Whether every task spawned so far has finished (true with none).
    pub fn all_finished(&self) -> bool {
        self.tasks.borrow().iter().all(|slot| slot.finished)
    }

    /// Runs for `duration` of virtual time.
    pub fn run_for(&self, duration: Duration) {
        let deadline = self.time.now_ns().saturating_add(duration_ns(duration));
        self.drive(deadline, || false);
    }

    /// Runs until virtual time reads `end_us`, or earlier once every task has finished.
    pub fn run_until_us(&self, end_us: u64) {
        self.drive(end_us.saturating_mul(1_000), || self.all_finished());
    }

    /// Runs until `condition` holds (checked whenever every task is idle) or nothing is left
    /// to happen. Returns whether the condition held. Loops forever if tasks keep time
    /// moving and the condition never holds; prefer `run_until_or` in tests.
    pub fn run_until(&self, condition: impl FnMut() -> bool) -> bool {
        self.drive(u64::MAX, condition)
    }

    /// Like `run_until`, but gives up after `limit` of virtual time.
    pub fn run_until_or(&self, limit: Duration, condition: impl FnMut() -> bool) -> bool {
        let deadline = self.time.now_ns().saturating_add(duration_ns(limit));
        self.drive(deadline, condition)
    }

    fn drive(&self, deadline_ns: u64, mut stop: impl FnMut() -> bool) -> bool {
        loop {
            self.poll_ready();
            if stop() {
                return true;
            }
            let next = self.time.next_due_ns(&*self.events.borrow());
            match next {
                Some(t) if t <= deadline_ns => {
                    self.time.advance_one(t, &mut *self.events.borrow_mut());
                }
                _ => {
                    if deadline_ns != u64::MAX {
                        self.time
                            .advance_to(deadline_ns, &mut *self.events.borrow_mut());
                    }
                    self.poll_ready();
                    return stop();
                }
            }
        }
    }

    /// Replaces the ready queue by every unfinished task in spawn order (a wake-up for
    /// everyone: the order does not depend on who was woken first).
    fn schedule_all(&self) {
        let tasks = self.tasks.borrow();
        if let Ok(mut queue) = self.ready.queue.lock() {
            queue.clear();
            for (index, slot) in tasks.iter().enumerate() {
                if !slot.finished {
                    slot.waker.scheduled.store(true, Ordering::Release);
                    queue.push(index);
                }
            }
        }
    }

    /// Polls woken tasks until none is woken.
    fn poll_ready(&self) {
        loop {
            if self.time.take_everyone_due() {
                self.schedule_all();
            }
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
                let pending = future.as_mut().poll(&mut cx).is_pending();
                if let Some(slot) = self.tasks.borrow_mut().get_mut(index) {
                    if pending {
                        slot.future = Some(future);
                    } else {
                        slot.finished = true;
                    }
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
        let time = VirtualTime::new();
        let ex = Executor::new(time.clone());
        let log = Rc::new(RefCell::new(Vec::new()));
        for (name, period_us) in [("a", 300u64), ("b", 500)] {
            let (time, log) = (time.clone(), log.clone());
            ex.spawn(async move {
                for _ in 0..3 {
                    time.sleep_ns(period_us * 1_000).await;
                    log.borrow_mut().push((name, time.now_us()));
                }
            });
        }
        ex.run_for(Duration::from_secs(3600));
        assert_eq!(time.now(), Duration::from_secs(3600));
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
        let time = VirtualTime::new();
        let ex = Executor::new(time.clone());
        let spawner = ex.spawner();
        let t = time.clone();
        let outer = ex.spawn(async move {
            let inner = spawner.spawn(async move {
                t.sleep_ns(2_500).await;
                21
            });
            inner.await * 2
        });
        assert!(ex.run_until_or(Duration::from_millis(1), || outer.is_finished()));
        assert_eq!(outer.take(), Some(42));
        assert_eq!(time.now(), Duration::from_nanos(2_500));
    }

    #[test]
    fn run_until_reports_a_condition_that_can_no_longer_become_true() {
        let time = VirtualTime::new();
        let ex = Executor::new(time.clone());
        let t = time.clone();
        let task = ex.spawn(async move {
            t.sleep_ns(1_000).await;
            7
        });
        assert!(!ex.run_until(|| false));
        assert_eq!(time.now(), Duration::from_micros(1));
        assert!(task.is_finished());
        assert_eq!(task.take(), Some(7));
        assert_eq!(task.take(), None);
        assert!(ex.run_until_or(Duration::from_millis(1), || true));
    }

    #[test]
    fn run_until_us_stops_at_the_end_or_when_every_task_is_done() {
        let time = VirtualTime::new();
        let ex = Executor::new(time.clone());
        let t = time.clone();
        ex.spawn(async move {
            let mut k = 0;
            loop {
                k += 10;
                t.sleep_until(k).await;
            }
        });
        ex.run_until_us(55);
        assert_eq!(time.now_us(), 55);
        let t = time.clone();
        let ex = Executor::new(time.clone());
        ex.spawn(async move { t.sleep_until(70).await });
        ex.run_until_us(1_000);
        assert_eq!(time.now_us(), 70, "stops when its only task is done");
    }

    #[test]
    fn a_wake_up_for_everyone_polls_every_task_in_spawn_order() {
        // Three futures that only check the time when polled (no waker): the second one is
        // also woken by its own sleep first, yet at 40 they still run in spawn order.
        let time = VirtualTime::new();
        let ex = Executor::new(time.clone());
        let log = Rc::new(RefCell::new(Vec::new()));
        for name in ["a", "b", "c"] {
            let (t, l) = (time.clone(), log.clone());
            ex.spawn(async move {
                if name == "b" {
                    t.sleep_until(40).await;
                }
                core::future::poll_fn(|_| {
                    if t.now_us() >= 40 {
                        Poll::Ready(())
                    } else {
                        Poll::Pending
                    }
                })
                .await;
                l.borrow_mut().push(name);
            });
        }
        time.wake_all_at(40);
        ex.run_until_us(1_000);
        assert_eq!(*log.borrow(), vec!["a", "b", "c"]);
    }

    #[test]
    fn a_wake_up_for_everyone_polls_tasks_without_wakers() {
        let time = VirtualTime::new();
        let ex = Executor::new(time.clone());
        let (t, seen) = (time.clone(), Rc::new(Cell::new(0)));
        let s = seen.clone();
        ex.spawn(async move {
            core::future::poll_fn(|_| {
                if t.now_us() >= 40 {
                    s.set(t.now_us());
                    Poll::Ready(())
                } else {
                    Poll::Pending
                }
            })
            .await;
        });
        time.wake_all_at(40);
        ex.run_until_us(1_000);
        assert_eq!(seen.get(), 40);
    }
}
