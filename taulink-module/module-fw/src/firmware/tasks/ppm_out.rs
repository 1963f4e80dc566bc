//! PPM output in the receiver role: each frame from the module core (already latched at
//! the frame boundary, so never a mix of old and new values) is loaded into PWM0 as a
//! waveform sequence (one PWM period per slot, 1 µs ticks) and played once; the next
//! frame starts when this one's length has passed. The core ends every frame with a
//! pulse-free tail slot, so starting a frame a little late (RTC ticks are 30.5 µs) only
//! stretches the sync gap, and stopping the old sequence never cuts a pulse.

use defmt::error;
use embassy_nrf::gpio::Level;
use embassy_nrf::pwm::{
    self, CounterMode, Prescaler, SequenceConfig, SequenceLoad, SequencePwm, SingleSequenceMode,
    SingleSequencer,
};
use embassy_time::{Duration, Instant, Timer};

use super::supervisor::{Watched, check_in};
use crate::firmware::board::PpmOut;
use crate::firmware::shared::with_app;

/// Four words per slot, up to 16 channels plus sync and tail.
const WAVEFORM_WORDS: usize = 4 * (16 + 2);
/// Negative-going pulses (idle high), the common convention: EdgeTX's default polarity "−"
/// (`radio/src/pulses/ppm.cpp`).
const PULSE_HIGH: bool = false;
/// Idle re-check period while there is nothing to send.
const IDLE: Duration = Duration::from_micros(22_500);

#[embassy_executor::task]
pub async fn ppm_out_task(out: PpmOut) {
    let mut config = pwm::Config::default();
    config.counter_mode = CounterMode::Up;
    // 16 MHz / 16 = 1 MHz: one count per µs, COUNTERTOP up to 32 767 µs.
    config.prescaler = Prescaler::Div16;
    config.sequence_load = SequenceLoad::Waveform;
    config.ch0_idle_level = if PULSE_HIGH { Level::Low } else { Level::High };
    let Ok(mut pwm) = SequencePwm::new_1ch(out.pwm, out.pin, config) else {
        error!("PWM0 refused the PPM configuration");
        return;
    };
    // EasyDMA reads the sequence from RAM while it plays: it lives here, in the task.
    let mut words = [0u16; WAVEFORM_WORDS];
    let mut next_start = Instant::now();
    loop {
        check_in(Watched::PpmOut);
        let frame = with_app(|app| app.next_ppm_frame()).flatten();
        let Some(sequence) = frame
            .and_then(|f| f.write_waveform(&mut words, PULSE_HIGH))
            .and_then(|count| words.get(..count))
        else {
            // No values yet, or failsafe with "stop pulses": the pin idles.
            next_start = Instant::now() + IDLE;
            Timer::at(next_start).await;
            continue;
        };
        let length_us = frame.map_or(22_500, |f| f.length_us());
        let sequencer = SingleSequencer::new(&mut pwm, sequence, SequenceConfig::default());
        if let Err(e) = sequencer.start(SingleSequenceMode::Times(1)) {
            error!("PPM sequence refused: {}", e);
        }
        next_start += Duration::from_micros(u64::from(length_us));
        // Fell behind (a long flash erase): restart the schedule instead of bursting.
        if next_start < Instant::now() {
            next_start = Instant::now() + Duration::from_micros(u64::from(length_us));
        }
        Timer::at(next_start).await;
        // Dropping the sequencer stops PWM0 during the pulse-free tail.
        drop(sequencer);
    }
}
