//! Virtual time and a deterministic single-threaded executor: every task is polled, then
//! time jumps to the earliest registered wake-up. Nothing real ever sleeps.

use std::cell::RefCell;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::future::Future;
use std::pin::Pin;
use std::rc::Rc;
use std::task::{Context, Poll, Waker};

use crate::link::LinkClock;

#[derive(Debug, Default)]
struct TimeState {
    now_us: u64,
    wakeups: BinaryHeap<Reverse<u64>>,
}

/// Shared virtual time (cheap to clone).
#[derive(Clone, Debug, Default)]
pub struct VirtualTime {
    state: Rc<RefCell<TimeState>>,
}

impl VirtualTime {
    /// Time starting at 0.
    pub fn new() -> Self {
        Self::default()
    }

    /// Current virtual time.
    pub fn now_us(&self) -> u64 {
        self.state.borrow().now_us
    }

    /// Asks the executor to poll everything again at `t_us`.
    pub fn wake_at(&self, t_us: u64) {
        let mut s = self.state.borrow_mut();
        if t_us > s.now_us {
            s.wakeups.push(Reverse(t_us));
        }
    }

    /// A future that completes at `deadline_us`.
    pub fn sleep_until(&self, deadline_us: u64) -> Sleep {
        Sleep {
            time: self.clone(),
            deadline_us,
            registered: false,
        }
    }

    fn advance(&self, limit_us: u64) -> bool {
        let mut s = self.state.borrow_mut();
        let now = s.now_us;
        while let Some(Reverse(t)) = s.wakeups.peek().copied() {
            if t > now {
                break;
            }
            s.wakeups.pop();
        }
        // Peek first: a wake-up beyond the limit stays queued for the next `run_until`.
        match s.wakeups.peek().copied() {
            Some(Reverse(t)) if t <= limit_us => {
                s.wakeups.pop();
                s.now_us = t;
                true
            }
            _ => {
                s.now_us = limit_us.max(now);
                false
            }
        }
    }
}

/// Future of [`VirtualTime::sleep_until`].
#[derive(Debug)]
pub struct Sleep {
    time: VirtualTime,
    deadline_us: u64,
    registered: bool,
}

impl Future for Sleep {
    type Output = ();

    fn poll(mut self: Pin<&mut Self>, _cx: &mut Context<'_>) -> Poll<()> {
        if self.time.now_us() >= self.deadline_us {
            return Poll::Ready(());
        }
        if !self.registered {
            self.time.wake_at(self.deadline_us);
            self.registered = true;
        }
        Poll::Pending
    }
}

/// A [`LinkClock`] on virtual time, optionally offset and drifting like a real crystal.
#[derive(Clone, Debug)]
pub struct MockClock {
    time: VirtualTime,
    offset_us: u64,
}

impl MockClock {
    /// A clock reading virtual time plus `offset_us` (each end boots at a different time).
    pub fn new(time: VirtualTime, offset_us: u64) -> Self {
        Self { time, offset_us }
    }
}

impl LinkClock for MockClock {
    fn now_us(&self) -> u64 {
        self.time.now_us() + self.offset_us
    }

    async fn sleep_until_us(&mut self, deadline_us: u64) {
        self.time
            .sleep_until(deadline_us.saturating_sub(self.offset_us))
            .await;
    }
}

/// A task: any future; its output is ignored.
pub type Task<'a> = Pin<Box<dyn Future<Output = ()> + 'a>>;

/// The executor: owns the tasks, polls them all on every time step.
pub struct Executor<'a> {
    time: VirtualTime,
    tasks: Vec<Option<Task<'a>>>,
}

impl<'a> Executor<'a> {
    /// An executor on `time`.
    pub fn new(time: VirtualTime) -> Self {
        Self {
            time,
            tasks: Vec::new(),
        }
    }

    /// Adds a task.
    pub fn spawn(&mut self, task: impl Future<Output = ()> + 'a) {
        self.tasks.push(Some(Box::pin(task)));
    }

    /// Runs until virtual time reaches `end_us` or every task has finished or is stuck.
    pub fn run_until(&mut self, end_us: u64) {
        let mut cx = Context::from_waker(Waker::noop());
        loop {
            for slot in self.tasks.iter_mut() {
                if let Some(task) = slot
                    && task.as_mut().poll(&mut cx).is_ready()
                {
                    *slot = None;
                }
            }
            if self.tasks.iter().all(Option::is_none) || !self.time.advance(end_us) {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sleeps_interleave_in_virtual_time() {
        let time = VirtualTime::new();
        let log = Rc::new(RefCell::new(Vec::new()));
        let mut ex = Executor::new(time.clone());
        for (name, period) in [("a", 3u64), ("b", 5)] {
            let (time, log) = (time.clone(), log.clone());
            ex.spawn(async move {
                for k in 1..=3 {
                    time.sleep_until(k * period).await;
                    log.borrow_mut().push((time.now_us(), name));
                }
            });
        }
        ex.run_until(100);
        assert_eq!(
            *log.borrow(),
            vec![(3, "a"), (5, "b"), (6, "a"), (9, "a"), (10, "b"), (15, "b")]
        );
        assert_eq!(time.now_us(), 15);
    }

    #[test]
    fn stops_at_the_end_time() {
        let time = VirtualTime::new();
        let mut ex = Executor::new(time.clone());
        let t = time.clone();
        ex.spawn(async move {
            let mut k = 0;
            loop {
                k += 10;
                t.sleep_until(k).await;
            }
        });
        ex.run_until(55);
        assert_eq!(time.now_us(), 55);
    }
}
