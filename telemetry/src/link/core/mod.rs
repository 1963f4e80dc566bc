//! The pure (sans-IO) state machines of both link ends. They are told the time and what the
//! radio did, and answer with the next [`Step`]; the async loops in `link::master` and
//! `link::follower` only carry these steps out.

pub mod follower;
pub mod master;
#[cfg(test)]
mod tests;

pub use follower::Follower;
pub use master::Master;

/// Telemetry bytes each end can queue for sending.
pub const STREAM_TX_BYTES: usize = 1024;
/// Telemetry bytes each end can hold received and unread.
pub const STREAM_RX_BYTES: usize = 1024;
/// The longest single [`Step::Listen`] either end plans. A follower acquiring dwells a whole
/// hop cycle on one channel (660 ms at L50); it does so in windows of at most this length on
/// the same channel, so the loop hands control back (and runs its hooks, where the firmware
/// checks in with its watchdog) at least this often in every state and rate mode.
pub const MAX_LISTEN_US: u64 = 50_000;

/// What a link end does next, in absolute times of its clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Step {
    /// Send the `len` bytes the state machine wrote into the frame buffer, starting at `at_us`.
    Transmit {
        /// Grid channel.
        channel: u8,
        /// Start of transmission (the loop sleeps until then).
        at_us: u64,
        /// Frame length.
        len: usize,
    },
    /// Listen from `from_us` until `until_us`.
    Listen {
        /// Grid channel.
        channel: u8,
        /// Start listening (the loop sleeps until then).
        from_us: u64,
        /// Stop listening.
        until_us: u64,
    },
    /// Nothing to do this slot.
    Idle,
}
