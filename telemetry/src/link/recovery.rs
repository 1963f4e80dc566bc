//! The link loops' radio-health policy, one for both ends: a periodic `check_health`, and
//! after a failed step a short wait and a re-init (`PacketRadio::recover`), giving up — the
//! session ends — only after [`MAX_CONSECUTIVE_RADIO_ERRORS`] failures in a row.

use super::core::{HEALTH_CHECK_PERIOD_US, MAX_CONSECUTIVE_RADIO_ERRORS, RADIO_RETRY_US};
use super::radio::{LinkClock, PacketRadio, RadioConfig};

/// What a loop keeps between steps.
pub(crate) struct Recovery {
    failures: u32,
    next_health_us: u64,
}

impl Recovery {
    /// The first health check one period after `now_us`.
    pub(crate) fn new(now_us: u64) -> Self {
        Self {
            failures: 0,
            next_health_us: now_us + HEALTH_CHECK_PERIOD_US,
        }
    }

    /// After a step that gave `result`: a health check when one is due; on a failure
    /// `on_error` (the state machine counts it), a wait and a re-init of the radio to
    /// `config`. `Err` once the failures in a row reach the bound.
    pub(crate) async fn after_step<R: PacketRadio, C: LinkClock>(
        &mut self,
        radio: &mut R,
        clock: &mut C,
        config: &RadioConfig,
        mut result: Result<(), R::Error>,
        mut on_error: impl FnMut(),
    ) -> Result<(), R::Error> {
        if result.is_ok() && clock.now_us() >= self.next_health_us {
            self.next_health_us = clock.now_us() + HEALTH_CHECK_PERIOD_US;
            result = radio.check_health().await;
        }
        let Err(e) = result else {
            self.failures = 0;
            return Ok(());
        };
        self.fail(e, &mut on_error)?;
        clock.sleep_until_us(clock.now_us() + RADIO_RETRY_US).await;
        if let Err(e) = radio.recover(config).await {
            self.fail(e, &mut on_error)?;
        }
        Ok(())
    }

    fn fail<E>(&mut self, e: E, on_error: &mut impl FnMut()) -> Result<(), E> {
        self.failures += 1;
        on_error();
        if self.failures >= MAX_CONSECUTIVE_RADIO_ERRORS {
            Err(e)
        } else {
            Ok(())
        }
    }
}
