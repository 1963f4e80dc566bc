//! Virtual time: the current instant (ns) and the wake-ups registered for later instants.
//!
//! Time only moves forward, through [`VirtualTime::advance_one`]/[`VirtualTime::advance_to`]
//! (the executor, or a world that busy-waits): first the attached world's events due at the
//! new instant run ([`Events`]), then the wake-ups due fire, earliest first and in
//! registration order at one instant, so a trace never depends on anything but the order
//! things were asked for.

use core::cmp::Ordering;
use core::future::Future;
use core::pin::Pin;
use core::task::{Context, Poll, Waker};
use core::time::Duration;
use std::cell::RefCell;
use std::collections::BinaryHeap;
use std::rc::Rc;

/// What happens in a simulated world besides wake-ups (si4432-sim's chips: a byte on air, a
/// PLL settling). The executor and [`VirtualTime::advance_to`] stop at each of its instants.
pub trait Events {
    /// The earliest instant something is due, ns (None: nothing scheduled).
    fn next_due_ns(&self) -> Option<u64>;
    /// Do everything due now (time already stands at the new instant; wake-ups due at it
    /// fire after this returns).
    fn process_due(&mut self);
}

/// A world with no events of its own (the packet-level mock: only wake-ups move time).
pub(crate) struct NoEvents;

impl Events for NoEvents {
    fn next_due_ns(&self) -> Option<u64> {
        None
    }

    fn process_due(&mut self) {}
}

/// One registered wake-up: a task's waker, or none for "poll every task".
#[derive(Debug)]
struct WakeUp {
    deadline_ns: u64,
    seq: u64,
    waker: Option<Waker>,
}

impl PartialEq for WakeUp {
    fn eq(&self, other: &Self) -> bool {
        (self.deadline_ns, self.seq) == (other.deadline_ns, other.seq)
    }
}
impl Eq for WakeUp {}
impl PartialOrd for WakeUp {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for WakeUp {
    // Reversed, so the max-heap pops the earliest deadline (then the first registered) first.
    fn cmp(&self, other: &Self) -> Ordering {
        (other.deadline_ns, other.seq).cmp(&(self.deadline_ns, self.seq))
    }
}

#[derive(Debug, Default)]
struct TimeState {
    now_ns: u64,
    wakeups: BinaryHeap<WakeUp>,
    seq: u64,
    /// A wake-up without a waker fired: the executor polls every task next.
    everyone_due: bool,
}

/// Shared virtual time (cheap to clone; every clone is the same clock).
#[derive(Clone, Debug, Default)]
pub struct VirtualTime {
    state: Rc<RefCell<TimeState>>,
}

impl VirtualTime {
    /// Time starting at 0.
    pub fn new() -> Self {
        Self::default()
    }

    /// Current virtual time, ns.
    pub fn now_ns(&self) -> u64 {
        self.state.borrow().now_ns
    }

    /// Current virtual time, µs (rounded down).
    pub fn now_us(&self) -> u64 {
        self.now_ns() / 1_000
    }

    /// Current virtual time.
    pub fn now(&self) -> Duration {
        Duration::from_nanos(self.now_ns())
    }

    /// A future that completes `ns` after now.
    pub fn sleep_ns(&self, ns: u64) -> Sleep {
        self.sleep_until_ns(self.now_ns().saturating_add(ns))
    }

    /// A future that completes when virtual time reaches `deadline_ns`.
    pub fn sleep_until_ns(&self, deadline_ns: u64) -> Sleep {
        Sleep {
            time: self.clone(),
            deadline_ns,
            registered: None,
        }
    }

    /// A future that completes when virtual time reaches `deadline_us` (the packet-level
    /// mock's unit).
    pub fn sleep_until(&self, deadline_us: u64) -> Sleep {
        self.sleep_until_ns(deadline_us.saturating_mul(1_000))
    }

    /// Wakes `waker` when virtual time reaches `deadline_ns`.
    pub fn wake_at_ns(&self, deadline_ns: u64, waker: Waker) {
        self.push(deadline_ns, Some(waker));
    }

    /// Polls every task at `t_us` (for futures that check the world when polled instead of
    /// registering a waker: the packet mock's radio). A time not after now is ignored.
    pub fn wake_all_at(&self, t_us: u64) {
        let t_ns = t_us.saturating_mul(1_000);
        if t_ns > self.now_ns() {
            self.push(t_ns, None);
        }
    }

    fn push(&self, deadline_ns: u64, waker: Option<Waker>) {
        let mut s = self.state.borrow_mut();
        s.seq += 1;
        let seq = s.seq;
        s.wakeups.push(WakeUp {
            deadline_ns,
            seq,
            waker,
        });
    }

    /// The earliest registered wake-up, ns.
    pub fn next_wakeup_ns(&self) -> Option<u64> {
        self.state.borrow().wakeups.peek().map(|w| w.deadline_ns)
    }

    /// The earliest instant anything is due: a wake-up or one of `events`.
    pub fn next_due_ns(&self, events: &dyn Events) -> Option<u64> {
        match (events.next_due_ns(), self.next_wakeup_ns()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Moves to `t` (never backwards), runs `events` due there, then fires every wake-up due.
    pub fn advance_one(&self, t_ns: u64, events: &mut dyn Events) {
        {
            let mut s = self.state.borrow_mut();
            s.now_ns = s.now_ns.max(t_ns);
        }
        events.process_due();
        loop {
            let fired = {
                let mut s = self.state.borrow_mut();
                let now = s.now_ns;
                if s.wakeups.peek().is_some_and(|w| w.deadline_ns <= now) {
                    s.wakeups.pop()
                } else {
                    None
                }
            };
            match fired {
                Some(WakeUp {
                    waker: Some(waker), ..
                }) => waker.wake(),
                Some(WakeUp { waker: None, .. }) => self.state.borrow_mut().everyone_due = true,
                None => return,
            }
        }
    }

    /// Processes everything due up to `t` in time order (a busy-wait: no task runs), then
    /// stands at `t`.
    pub fn advance_to(&self, t_ns: u64, events: &mut dyn Events) {
        while let Some(next) = self.next_due_ns(events).filter(|&next| next <= t_ns) {
            self.advance_one(next, events);
        }
        let mut s = self.state.borrow_mut();
        s.now_ns = s.now_ns.max(t_ns);
    }

    /// Whether a wake-up for every task fired since the last call.
    pub(crate) fn take_everyone_due(&self) -> bool {
        core::mem::take(&mut self.state.borrow_mut().everyone_due)
    }
}

/// Future of [`VirtualTime::sleep_until_ns`]: completes when virtual time reaches its deadline.
pub struct Sleep {
    time: VirtualTime,
    deadline_ns: u64,
    /// The waker already registered (re-polls with the same waker add nothing).
    registered: Option<Waker>,
}

impl Future for Sleep {
    type Output = ();

    fn poll(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<()> {
        let this = self.get_mut();
        if this.time.now_ns() >= this.deadline_ns {
            return Poll::Ready(());
        }
        if !this
            .registered
            .as_ref()
            .is_some_and(|w| w.will_wake(cx.waker()))
        {
            this.time.wake_at_ns(this.deadline_ns, cx.waker().clone());
            this.registered = Some(cx.waker().clone());
        }
        Poll::Pending
    }
}

impl core::fmt::Debug for Sleep {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Sleep")
            .field("deadline_ns", &self.deadline_ns)
            .finish_non_exhaustive()
    }
}
