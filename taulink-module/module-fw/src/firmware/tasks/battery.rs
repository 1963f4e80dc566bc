//! Measures the radio battery (JR pin 3) once a second with the SAADC and hands it to the
//! core (handset report, low-battery LED).

use core::sync::atomic::{AtomicU16, Ordering};

use embassy_nrf::saadc::{ChannelConfig, Config, Gain, Reference, Saadc, Time};
use embassy_time::{Duration, Ticker};
use module_core::battery::battery_mv;

use super::supervisor::{Watched, check_in};
use crate::firmware::board::{Battery, Irqs};
use crate::firmware::shared::{carry_out, with_app};

/// Last radio battery voltage, mV (0 until the first sample).
pub static BATTERY_MV: AtomicU16 = AtomicU16::new(0);

#[embassy_executor::task]
pub async fn battery_task(battery: Battery) {
    let mut channel = ChannelConfig::single_ended(battery.pin);
    // Gain 1/6 with the internal 0.6 V reference: 3.6 V full scale (module_core::battery).
    channel.gain = Gain::Gain1_6;
    channel.reference = Reference::Internal;
    // 40 µs acquisition for the 18 kΩ source impedance of the divider (PS §6.23.6 table).
    channel.time = Time::_40US;
    let mut adc = Saadc::new(battery.saadc, Irqs, Config::default(), [channel]);
    adc.calibrate().await;
    let mut ticker = Ticker::every(Duration::from_millis(50));
    let mut ticks = 0u32;
    loop {
        check_in(Watched::Battery);
        if ticks.is_multiple_of(20) {
            let mut sample = [0i16; 1];
            adc.sample(&mut sample).await;
            let [raw] = sample;
            let mv = battery_mv(raw);
            BATTERY_MV.store(mv, Ordering::Relaxed);
            // To the handset (S.Port A2) and, when low, the LED.
            carry_out(with_app(|app| app.on_module_battery(mv)).flatten());
            if ticks.is_multiple_of(20 * 60) {
                defmt::info!("radio battery {} mV", mv);
            }
        }
        ticks = ticks.wrapping_add(1);
        ticker.next().await;
    }
}
