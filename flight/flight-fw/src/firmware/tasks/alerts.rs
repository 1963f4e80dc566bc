//! Sounds the app's tone (`FlightApp::on_alert_tick`, every 10 ms) through the DAC into the
//! video transmitter's audio (PA4): a sine table played by DMA, paced by TIM6 so the pitch
//! is TIM6's rate / 130 — and on the buzzer output.

use embassy_futures::select::{Either, select};
use embassy_stm32::dac::{DacChannel, Value, ValueArray};
use embassy_stm32::gpio::Output;
use embassy_stm32::mode::Async;
use embassy_stm32::peripherals::TIM6;
use embassy_stm32::timer::low_level::Timer;
use embassy_time::{Duration, Ticker};
use flight_app::alerts::{DAC_SAMPLES_PER_CYCLE, dac_sample_period_ticks};

use crate::firmware::shared::{now_ms, with_app};

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

#[embassy_executor::task]
pub async fn alerts_task(mut speaker: Speaker) {
    // At rest the output sits at the sine's centre before the first tone too: from the DAC's
    // 0 V reset value the first tone would start with a step of half a volt into the video
    // transmitter's audio (a click), and end with another back to the centre.
    speaker.dac.set(Value::Bit12Right(CENTRE_COUNTS));
    let mut ticker = Ticker::every(Duration::from_millis(10));
    let mut frequency = 0u16;
    loop {
        // Play the current pitch until the next change.
        let table: &[u16] = speaker.table;
        let changed = async {
            loop {
                ticker.next().await;
                let next = with_app(|a| a.on_alert_tick(now_ms())).unwrap_or(0);
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
