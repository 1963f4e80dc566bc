//! PPM capture from the handset (nRF52840 Product Specification: GPIOTE, PPI, TIMER): each
//! falling edge on P1.04 triggers,
//! through GPIOTE and PPI, TIMER1's CAPTURE[0] in hardware, so the timestamp is exact to
//! 1 µs whatever the interrupt latency; the task only reads CC[0] after the edge and hands
//! it to the decoder in the module core. Edges come at least every 2.25 ms inside a frame,
//! far slower than the wake-up, so CC[0] is read before the next capture overwrites it.
//! A frame that agrees with the last one goes out at the edge closing its last channel
//! (`App::on_ppm_edge`). When the core has one waiting for its sync gap to be proven instead
//! (`App::ppm_deadline_us`) the task also wakes at that deadline, so the frame goes out
//! ≈ 8 ms before the next frame's first edge would have released it.

use embassy_nrf::gpio::Pull;
use embassy_nrf::gpiote::{InputChannel, InputChannelPolarity};
use embassy_nrf::ppi::Ppi;
use embassy_nrf::timer::{Frequency, Timer};
use embassy_time::{Duration, with_timeout};

use super::supervisor::{Watched, check_in};
use crate::firmware::board::PpmIn;
use crate::firmware::shared::with_app;

/// Without edges the loss detection still runs this often.
const IDLE_TICK: Duration = Duration::from_millis(50);

#[embassy_executor::task]
pub async fn ppm_in_task(ppm: PpmIn) {
    let timer = Timer::new(ppm.timer);
    timer.set_frequency(Frequency::F1MHz);
    let mut edge = InputChannel::new(
        ppm.edge_channel,
        ppm.pin,
        Pull::None,
        InputChannelPolarity::HiToLo,
    );
    // Free-running: the decoder works on wrapping differences, so no clear on capture.
    let mut capture = Ppi::new_one_to_one(
        ppm.capture_channel,
        edge.event_in(),
        timer.cc(0).task_capture(),
    );
    capture.enable();
    timer.start();
    loop {
        check_in(Watched::PpmIn);
        // Until the release deadline (TIMER1 clock, wrapping) if one is due before the idle
        // tick; a deadline already passed wakes at once.
        let wait = with_app(|app| app.ppm_deadline_us())
            .flatten()
            .map(|deadline| {
                let left = deadline.wrapping_sub(timer.cc(1).capture());
                if left > u32::MAX / 2 { 0 } else { left }
            })
            .filter(|us| u64::from(*us) < IDLE_TICK.as_micros())
            .map_or(IDLE_TICK, |us| Duration::from_micros(u64::from(us)));
        match with_timeout(wait, edge.wait()).await {
            Ok(()) => {
                let timestamp_us = timer.cc(0).read();
                with_app(|app| {
                    app.on_ppm_edge(timestamp_us);
                    app.on_ppm_tick(timestamp_us);
                });
            }
            Err(_) => {
                // CAPTURE[1] by software: "now" on the same clock as the edges.
                let now_us = timer.cc(1).capture();
                with_app(|app| app.on_ppm_tick(now_us));
            }
        }
    }
}
