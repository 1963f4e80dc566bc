//! The pure (sans-IO) state machines of both link ends. They are told the time and what the
//! radio did, and answer with the next [`Step`]; the async loops in `link::master` and
//! `link::follower` only carry these steps out.

mod end;
mod epoch;
pub mod follower;
pub mod master;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_budget;
#[cfg(test)]
mod tests_epoch;

pub use epoch::counter as frame_counter;
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
/// Consecutive radio errors (bus errors, a chip reset, FIFO errors, TX timeouts) a link
/// session rides through — re-configuring the radio after each and carrying on — before the
/// loop gives up and returns the error. A success resets the count.
pub const MAX_CONSECUTIVE_RADIO_ERRORS: u32 = 8;
/// After a radio error the loop waits this long before the next step, so a radio that fails
/// at once (unpowered, browning out) is retried over ~`MAX_CONSECUTIVE_RADIO_ERRORS` × this,
/// not in a burst of microseconds; short enough for the hooks' 50 ms cadence.
pub const RADIO_RETRY_US: u64 = 10_000;
/// How often the loops ask the radio to [`check_health`](crate::link::PacketRadio::check_health)
/// (for a chip that reset without any operation failing).
pub const HEALTH_CHECK_PERIOD_US: u64 = 1_000_000;

/// Extra frame bytes a tag takes over the link CRC.
pub(crate) const fn tag_extra(keyed: bool) -> usize {
    if keyed {
        crate::link::auth::TAG_BYTES - crate::frame::CRC_BYTES
    } else {
        0
    }
}

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
