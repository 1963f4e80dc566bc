//! The HM-10 on UARTE1: the boot-time AT script the core builds (`App::hm10_script`: with the
//! pairing PIN; the UARTE re-opened at each baud rate it asks for), then the relay of records both ways through the core, whose
//! bounded queues are all the phone side touches, so it cannot stall the radio.

use embassy_futures::join::join;
use embassy_nrf::uarte::UarteTx;
use embassy_time::{Duration, Timer, with_timeout};
use module_core::hm10::at::Action;
use module_core::hm10::relay::MAX_FRAME_LEN;

use super::supervisor::{Watched, check_in, idle};
use crate::firmware::board::Hm10;
use crate::firmware::shared::{now_ms, with_app};

#[embassy_executor::task]
pub async fn hm10_task(mut hm10: Hm10) {
    // The core's script: name, notifications and the pairing PIN with bonding (the set PIN,
    // else this chip's factory PIN from its FICR DEVICEID).
    let Some(mut script) = with_app(|app| app.hm10_script(now_ms(), device_id())) else {
        idle(Watched::Hm10).await
    };
    let outcome = 'script: loop {
        let baud = script.baud();
        let (mut tx, mut rx) = hm10.open(baud);
        let (mut received, mut count) = ([0u8; 32], 0);
        loop {
            check_in(Watched::Hm10);
            // The driver reads at most `received.len()`; a count past it reads as nothing.
            let reply = received.get(..count).unwrap_or(&[]);
            match script.poll(now_ms(), reply) {
                Action::SetBaud(next) if next != baud => break,
                Action::SetBaud(_) => count = 0,
                Action::Send(command) => {
                    count = 0;
                    write(&mut tx, command).await;
                }
                Action::Wait { until_ms } => {
                    // Short slices so the supervisor keeps hearing from us.
                    let wait =
                        Duration::from_millis(until_ms.wrapping_sub(now_ms()).clamp(1, 50).into());
                    count = with_timeout(wait, rx.read_until_idle(&mut received))
                        .await
                        .map_or(0, |r| r.unwrap_or(0));
                }
                Action::Done(outcome) => break 'script outcome,
            }
        }
    };
    defmt::info!("HM-10: {}", outcome);
    let Some(baud) = with_app(|app| app.on_hm10_configured(outcome)).flatten() else {
        // Nothing (usable) fitted: stay registered with the supervisor, do nothing.
        idle(Watched::Hm10).await
    };
    let (mut tx, mut rx) = hm10.open(baud);
    let receive = async {
        let mut buffer = [0u8; 64];
        loop {
            // A framing or overrun error: the COBS framing resynchronises by itself; pause so
            // a line stuck in error cannot starve the other tasks.
            let Ok(count) = rx.read_until_idle(&mut buffer).await else {
                Timer::after_millis(1).await;
                continue;
            };
            // The driver reads at most `buffer.len()`, so the range always exists.
            if let Some(bytes) = buffer.get(..count) {
                with_app(|app| app.on_phone_bytes(bytes));
            }
        }
    };
    let send = async {
        let mut frame = [0u8; MAX_FRAME_LEN];
        loop {
            check_in(Watched::Hm10);
            while let Some(count) = with_app(|app| app.next_phone_frame(&mut frame)).flatten() {
                // The relay writes at most `frame.len()`; a count past it sends nothing.
                let Some(bytes) = frame.get(..count) else {
                    break;
                };
                write(&mut tx, bytes).await;
            }
            Timer::after_millis(20).await;
        }
    };
    join(receive, send).await;
}

/// The nRF52840's 64-bit unique device ID (FICR DEVICEID[0..2]), programmed at the factory.
fn device_id() -> u64 {
    let ficr = embassy_nrf::pac::FICR;
    let low = ficr.deviceid(0).read();
    let high = ficr.deviceid(1).read();
    (u64::from(high) << 32) | u64::from(low)
}

async fn write(tx: &mut UarteTx<'_>, bytes: &[u8]) {
    if tx.write(bytes).await.is_err() {
        defmt::warn!("HM-10 write failed");
    }
}
