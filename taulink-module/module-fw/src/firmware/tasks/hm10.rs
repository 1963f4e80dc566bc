//! The HM-10 on UARTE1: the boot-time AT script of `module_core::hm10::at`, then the relay
//! of telemetry records both ways through the module core. The UARTE is re-opened whenever
//! the script changes the baud rate. Sending and receiving run concurrently in the relay;
//! the phone side only ever touches bounded queues in the core, so it cannot stall the
//! radio.

use embassy_futures::join::join;
use embassy_nrf::uarte::{self, Baudrate, Uarte};
use embassy_time::{Duration, Timer, with_timeout};
use module_core::hm10::at::{Action, Configurator, Outcome};
use module_core::hm10::relay::MAX_FRAME_LEN;

use super::supervisor::{Watched, check_in};
use crate::firmware::board::{Hm10, Irqs};
use crate::firmware::shared::{now_ms, with_app};

/// The BLE name the phone app filters on.
const NAME: &str = "TauLink";

fn config(baud: u32) -> uarte::Config {
    let mut config = uarte::Config::default();
    config.baudrate = if baud == 9_600 {
        Baudrate::Baud9600
    } else {
        Baudrate::Baud115200
    };
    config
}

/// What ended one baud rate's session of the script.
enum Next {
    Baud(u32),
    Done(Outcome),
}

#[embassy_executor::task]
pub async fn hm10_task(mut hm10: Hm10) {
    let mut script = Configurator::new(NAME, now_ms());
    let mut baud = script.baud();
    let outcome = loop {
        match configure_at(&mut hm10, baud, &mut script).await {
            Next::Baud(next) => baud = next,
            Next::Done(outcome) => break outcome,
        }
    };
    defmt::info!("HM-10: {}", outcome);
    let relay_baud = match outcome {
        Outcome::Configured { baud } | Outcome::PhoneConnected { baud } => baud,
        Outcome::NoModule | Outcome::Failed { .. } => {
            // Nothing (usable) fitted: stay registered with the supervisor, do nothing.
            loop {
                check_in(Watched::Hm10);
                Timer::after(Duration::from_millis(50)).await;
            }
        }
    };
    if matches!(outcome, Outcome::PhoneConnected { .. }) {
        with_app(|app| app.on_phone_connected());
    }
    relay(&mut hm10, relay_baud).await;
}

async fn configure_at(hm10: &mut Hm10, baud: u32, script: &mut Configurator) -> Next {
    let (mut tx, mut rx) = Uarte::new(
        hm10.uarte.reborrow(),
        hm10.rx.reborrow(),
        hm10.tx.reborrow(),
        Irqs,
        config(baud),
    )
    .split_with_idle(
        hm10.idle_timer.reborrow(),
        hm10.idle_ppi_start.reborrow(),
        hm10.idle_ppi_stop.reborrow(),
    );
    let mut received = [0u8; 32];
    let mut count = 0;
    loop {
        check_in(Watched::Hm10);
        let bytes = received.get(..count).unwrap_or(&[]);
        match script.poll(now_ms(), bytes) {
            Action::SetBaud(next) if next == baud => count = 0,
            Action::SetBaud(next) => return Next::Baud(next),
            Action::Send(command) => {
                count = 0;
                if tx.write(command).await.is_err() {
                    defmt::warn!("HM-10 write failed");
                }
            }
            Action::Wait { until_ms } => {
                count = 0;
                // Short slices so the supervisor keeps hearing from us.
                let wait_ms = until_ms.wrapping_sub(now_ms()).clamp(1, 50);
                let read = rx.read_until_idle(&mut received);
                if let Ok(Ok(n)) =
                    with_timeout(Duration::from_millis(u64::from(wait_ms)), read).await
                {
                    count = n;
                }
            }
            Action::Done(outcome) => return Next::Done(outcome),
        }
    }
}

async fn relay(hm10: &mut Hm10, baud: u32) {
    let (mut tx, mut rx) = Uarte::new(
        hm10.uarte.reborrow(),
        hm10.rx.reborrow(),
        hm10.tx.reborrow(),
        Irqs,
        config(baud),
    )
    .split_with_idle(
        hm10.idle_timer.reborrow(),
        hm10.idle_ppi_start.reborrow(),
        hm10.idle_ppi_stop.reborrow(),
    );
    let receive = async {
        let mut buffer = [0u8; 64];
        loop {
            match rx.read_until_idle(&mut buffer).await {
                Ok(count) => {
                    let bytes = buffer.get(..count).unwrap_or(&[]);
                    with_app(|app| app.on_phone_bytes(bytes));
                }
                // A framing or overrun error: the COBS framing resynchronises by itself;
                // pause so a line stuck in error cannot starve the other tasks.
                Err(_) => Timer::after(Duration::from_millis(1)).await,
            }
        }
    };
    let send = async {
        let mut frame = [0u8; MAX_FRAME_LEN];
        loop {
            check_in(Watched::Hm10);
            while let Some(count) = with_app(|app| app.next_phone_frame(&mut frame)).flatten() {
                if tx.write(frame.get(..count).unwrap_or(&[])).await.is_err() {
                    defmt::warn!("HM-10 write failed");
                }
            }
            Timer::after(Duration::from_millis(20)).await;
        }
    };
    join(receive, send).await;
}
