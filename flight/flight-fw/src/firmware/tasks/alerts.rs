//! Sounds alerts through the DAC into the video transmitter's audio (PA4): a sine table
//! played by DMA, paced by TIM6 so the pitch is TIM6's rate / 130 — and on the buzzer
//! output. Battery alarms repeat while the battery stays low.

use embassy_futures::select::{Either, select};
use embassy_stm32::dac::{DacChannel, Value, ValueArray};
use embassy_stm32::gpio::Output;
use embassy_stm32::mode::Async;
use embassy_stm32::peripherals::TIM6;
use embassy_stm32::timer::low_level::Timer;
use embassy_time::{Duration, Instant, Ticker};
use flight_core::alerts::{Alert, DAC_SAMPLES_PER_CYCLE, TonePlayer, dac_sample_period_ticks};
use flight_core::battery::BatteryLevel;

use super::supervisor::{Watched, check_in};
use crate::firmware::signals::{ALERTS, BATTERY};

/// DAC output at rest (the sine's centre), 500 mV.
const CENTRE_COUNTS: u16 = 620;

/// The DAC channel, its pacing timer and the sine table (in RAM for the DMA).
pub struct Speaker {
    /// DAC1 channel 1 with DMA, triggered by TIM6 TRGO.
    pub dac: DacChannel<'static, Async>,
    /// TIM6, master mode "update".
    pub pacer: Timer<'static, TIM6>,
    /// One sine cycle.
    pub table: &'static [u16; DAC_SAMPLES_PER_CYCLE],
    /// The buzzer output (an active buzzer on the low-side FET of output 8): on while a
    /// tone sounds, so the same patterns are heard without the video link.
    pub buzzer: Output<'static>,
}

fn now_ms() -> u32 {
    Instant::now().as_millis() as u32
}

#[embassy_executor::task]
pub async fn alerts_task(mut speaker: Speaker) {
    let mut player = TonePlayer::new();
    let mut battery = BATTERY.receiver();
    let mut ticker = Ticker::every(Duration::from_millis(10));
    let mut frequency = 0u16;
    loop {
        // Play the current pitch until the next change.
        let table: &[u16] = speaker.table;
        let changed = async {
            loop {
                ticker.next().await;
                check_in(Watched::Alerts);
                while let Ok(alert) = ALERTS.try_receive() {
                    player.push(alert);
                }
                if let Some(b) = battery.as_mut().and_then(|r| r.try_get()) {
                    match b.level {
                        BatteryLevel::Critical => {
                            player.set_repeating(Some(Alert::BatteryCritical), 2_000)
                        }
                        BatteryLevel::Warning => {
                            player.set_repeating(Some(Alert::BatteryWarning), 10_000)
                        }
                        BatteryLevel::Ok => player.set_repeating(None, 0),
                    }
                }
                let next = player.tick(now_ms());
                if next != frequency {
                    return next;
                }
            }
        };
        let next = if frequency == 0 {
            changed.await
        } else {
            match select(
                speaker.dac.write(ValueArray::Bit12Right(table), true),
                changed,
            )
            .await
            {
                Either::First(()) => frequency, // circular transfers do not end
                Either::Second(next) => next,
            }
        };
        frequency = next;
        if frequency == 0 {
            speaker.buzzer.set_low();
        } else {
            speaker.buzzer.set_high();
        }
        match dac_sample_period_ticks(frequency, DAC_SAMPLES_PER_CYCLE) {
            Some(arr) => {
                let arr = arr.min(0xFFFF) as u16;
                speaker.pacer.regs_core().arr().write(|w| w.set_arr(arr));
                speaker.pacer.generate_update_event();
            }
            None => speaker.dac.set(Value::Bit12Right(CENTRE_COUNTS)),
        }
    }
}
