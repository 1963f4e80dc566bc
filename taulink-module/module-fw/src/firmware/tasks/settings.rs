//! Owns the settings flash: persists what the module core asks to save.
//!
//! NVMC erases stall the CPU (≤ 85 ms per page, PS §4.3.9); saves only happen after a bind,
//! and the PPM output keeps running in hardware meanwhile.

use embassy_embedded_hal::adapter::BlockingAsync;
use embassy_nrf::nvmc::Nvmc;
use embassy_time::{Duration, with_timeout};
use module_core::settings::SettingsStore;

use super::supervisor::{Watched, check_in};
use crate::firmware::shared::SAVE;

/// The store as the firmware builds it.
pub type Store = SettingsStore<BlockingAsync<Nvmc<'static>>>;

#[embassy_executor::task]
pub async fn settings_task(mut store: Store) {
    loop {
        check_in(Watched::Settings);
        let Ok(settings) = with_timeout(Duration::from_millis(50), SAVE.wait()).await else {
            continue;
        };
        match store.save(&settings).await {
            Ok(()) => defmt::info!("settings saved"),
            Err(e) => defmt::error!("settings not saved: {}", e),
        }
    }
}
