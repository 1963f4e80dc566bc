//! Audible alerts: which tone pattern says what, a player that sequences them by priority,
//! and the DAC waveform that carries them into the video transmitter's audio (and the
//! buzzer output).

mod patterns;
mod player;
mod waveform;

pub use patterns::{Alert, Tone};
pub use player::TonePlayer;
pub use waveform::{DAC_SAMPLES_PER_CYCLE, dac_sample_period_ticks, sine_table};
