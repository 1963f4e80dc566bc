//! The JR pin 5 line (UARTE0 behind the XOR and the tri-state buffer, hardware README),
//! driven as the module core's handset codec asks (`module_core::handset::LineMode`):
//!
//! * CRSF (EdgeTX): 400 kBd, not inverted, half duplex. The UARTE cannot share one wire, so
//!   the driver is re-created per direction (the UARTE has no half-duplex or inversion
//!   setting, and its pins can only change while it is disabled): the radio's frame is
//!   received with idle-line detection and goes to the CRSF decoder stamped with the idle
//!   time; then the responder's reply (DEVICE_INFO, timing, LINK_STATISTICS, sensors) is
//!   sent in the slot after the radio's frame (`JrLine::send` enables the buffer only for it).
//! * S.Port (57 600 Bd) / FrSky D (9600 Bd): inverted through the polarity pin, transmit
//!   only, frames pushed unpolled (a PPM module's telemetry: EdgeTX ≥ 2.11
//!   `radio/src/pulses/ppm.cpp` opens the S.Port pin receive-only; OpenTX 2.2/2.3 and
//!   EdgeTX ≤ 2.8 through the model's telemetry type); the scheduler in the core paces them
//!   (12 ms / 30 ms slots), this task asks every 2 ms.

use embassy_time::{Duration, Timer, with_timeout};
use module_core::handset::{LineMode, MAX_LINE_BURST};

use super::supervisor::{Watched, check_in, idle};
use crate::firmware::board::JrLine;
use crate::firmware::shared::{carry_out, now_us, with_app};

/// How often the push modes ask the scheduler (well under its 12 ms S.Port slot).
const PUSH_POLL: Duration = Duration::from_millis(2);

#[embassy_executor::task]
pub async fn jr_line_task(mut line: JrLine) {
    let mode = with_app(|app| app.handset().line_mode()).unwrap_or(LineMode::Off);
    defmt::info!("JR line: {}", mode);
    let mut frame = [0u8; 64];
    let mut reply = [0u8; MAX_LINE_BURST];
    loop {
        check_in(Watched::JrLine);
        match mode {
            LineMode::Crsf { baud } => {
                line.invert.set_low();
                line.driver_enable.set_low();
                let mut rx = line.receiver(baud);
                let received =
                    with_timeout(Duration::from_millis(50), rx.read_until_idle(&mut frame)).await;
                drop(rx);
                let Ok(Ok(count)) = received else {
                    continue;
                };
                // The driver reads at most `frame.len()` bytes, so the range always exists.
                let Some(received) = frame.get(..count) else {
                    continue;
                };
                let idle_us = now_us();
                let burst = with_app(|app| {
                    app.on_handset_bytes(idle_us, received);
                    app.on_handset_idle(idle_us);
                    app.next_handset_bytes(now_us(), &mut reply)
                });
                // No app (it is being replaced): nothing to send this window.
                if let Some(burst) = burst {
                    line.send(baud, burst).await;
                }
                // A save or bind asked for from the radio's device tool.
                while let Some(action) = with_app(|app| app.take_action()).flatten() {
                    carry_out(Some(action));
                }
            }
            LineMode::Push { baud } => {
                line.invert.set_high();
                if let Some(burst) = with_app(|app| app.next_handset_bytes(now_us(), &mut reply)) {
                    line.send(baud, burst).await;
                }
                Timer::after(PUSH_POLL).await;
            }
            LineMode::Off => idle(Watched::JrLine).await,
        }
    }
}
