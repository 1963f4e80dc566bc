//! Samples battery voltage (PC3) and current (PC2) at 20 Hz, runs the battery monitor, and
//! announces level changes.

use embassy_stm32::adc::{Adc, AnyAdcChannel, SampleTime};
use embassy_stm32::peripherals::ADC1;
use embassy_time::{Duration, Instant, Ticker};
use flight_core::alerts::Alert;
use flight_core::battery::{BatteryLevel, BatteryMonitor};

use super::supervisor::{Watched, check_in};
use crate::firmware::signals::{ALERTS, BATTERY};

/// The ADC and its two channels.
pub struct BatterySense {
    /// ADC1.
    pub adc: Adc<'static, ADC1>,
    /// PC3, VBAT through the divider.
    pub voltage: AnyAdcChannel<'static, ADC1>,
    /// PC2, current-sense amplifier.
    pub current: AnyAdcChannel<'static, ADC1>,
}

#[embassy_executor::task]
pub async fn battery_task(mut sense: BatterySense, mut monitor: BatteryMonitor) {
    let sender = BATTERY.sender();
    let mut ticker = Ticker::every(Duration::from_millis(50));
    loop {
        ticker.next().await;
        check_in(Watched::Battery);
        // 480 cycles: the 10 k source impedance needs a long sample time.
        let v = sense
            .adc
            .blocking_read(&mut sense.voltage, SampleTime::CYCLES480);
        let i = sense
            .adc
            .blocking_read(&mut sense.current, SampleTime::CYCLES480);
        let now_ms = Instant::now().as_millis() as u32;
        let status = monitor.update(now_ms, v, Some(i));
        if status.level_changed {
            let alert = match status.level {
                BatteryLevel::Critical => Some(Alert::BatteryCritical),
                BatteryLevel::Warning => Some(Alert::BatteryWarning),
                BatteryLevel::Ok => None,
            };
            if let Some(alert) = alert {
                // A full queue already holds alarms; the repeating one comes back anyway.
                let _ = ALERTS.try_send(alert);
            }
        }
        sender.send(status);
    }
}
