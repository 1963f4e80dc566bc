//! Samples battery voltage (PC3) and current (PC2) at 20 Hz and hands the raw counts to
//! `FlightApp::on_battery` (the monitor and its alarms live there).

use embassy_stm32::adc::{Adc, AnyAdcChannel, SampleTime};
use embassy_stm32::peripherals::ADC1;
use embassy_time::{Duration, Ticker};

use crate::firmware::shared::{now_ms, with_app};

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
pub async fn battery_task(mut sense: BatterySense) {
    let mut ticker = Ticker::every(Duration::from_millis(50));
    loop {
        ticker.next().await;
        // 480 cycles: the 10 k source impedance needs a long sample time.
        let v = sense
            .adc
            .blocking_read(&mut sense.voltage, SampleTime::CYCLES480);
        let i = sense
            .adc
            .blocking_read(&mut sense.current, SampleTime::CYCLES480);
        with_app(|a| a.on_battery(now_ms(), v, Some(i)));
    }
}
