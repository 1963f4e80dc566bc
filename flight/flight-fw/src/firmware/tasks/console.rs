//! The USB CDC console (VID/PID 0x20A0/0x415B as Tau Labs used): reads lines, runs them
//! through `flight_core::settings`' command language, prints the answers. Settings change in
//! RAM; `save` asks the storage task to write them. Both are refused while armed.

use core::fmt::Write;
use core::sync::atomic::Ordering;

use embassy_futures::join::join;
use embassy_stm32::peripherals::USB_OTG_FS;
use embassy_stm32::usb::Driver;
use embassy_usb::class::cdc_acm::{CdcAcmClass, State};
use embassy_usb::driver::EndpointError;
use embassy_usb::{Builder, Config};
use flight_core::settings::{
    Command, LineAssembler, Settings, parse_line, write_list, write_setting,
};
use heapless::String;
use static_cell::StaticCell;

use crate::firmware::signals::{
    ARMED, BATTERY, FLIGHT_STATE, LINK_INPUT, SAVE_REQUEST, SETTINGS, SETTINGS_CHANGED,
};

const HELP: &str = "help | list [prefix] | get NAME | set NAME VALUE [NAME VALUE]... | save | defaults | status\r\n";

struct Buffers {
    config_descriptor: [u8; 256],
    bos_descriptor: [u8; 256],
    control: [u8; 64],
    state: State<'static>,
}

static BUFFERS: StaticCell<Buffers> = StaticCell::new();

#[embassy_executor::task]
pub async fn console_task(driver: Driver<'static, USB_OTG_FS>) {
    let mut config = Config::new(0x20A0, 0x415B);
    config.manufacturer = Some("TauLink");
    config.product = Some("TauLink flight controller");
    config.max_power = 100;
    let buffers = BUFFERS.init(Buffers {
        config_descriptor: [0; 256],
        bos_descriptor: [0; 256],
        control: [0; 64],
        state: State::new(),
    });
    let mut builder = Builder::new(
        driver,
        config,
        &mut buffers.config_descriptor,
        &mut buffers.bos_descriptor,
        &mut [],
        &mut buffers.control,
    );
    let mut class = CdcAcmClass::new(&mut builder, &mut buffers.state, 64);
    let mut usb = builder.build();
    let session = async {
        loop {
            class.wait_connection().await;
            // A disconnect ends the session; wait for the next one.
            let _ = serve(&mut class).await;
        }
    };
    join(usb.run(), session).await;
}

async fn serve(
    class: &mut CdcAcmClass<'static, Driver<'static, USB_OTG_FS>>,
) -> Result<(), EndpointError> {
    let mut lines: LineAssembler<96> = LineAssembler::new();
    let mut packet = [0u8; 64];
    loop {
        let n = class.read_packet(&mut packet).await?;
        for &byte in packet.get(..n).unwrap_or(&[]) {
            // Overlong lines are refused whole, never cut (a cut line can mean something else).
            let Some(line) = lines.push(byte) else {
                continue;
            };
            let mut reply: String<2048> = String::new();
            match line {
                Ok(line) => answer(line.as_str(), &mut reply).await,
                Err(e) => {
                    let _ = writeln!(reply, "{e}");
                }
            }
            send(class, reply.as_bytes()).await?;
        }
    }
}

async fn send(
    class: &mut CdcAcmClass<'static, Driver<'static, USB_OTG_FS>>,
    bytes: &[u8],
) -> Result<(), EndpointError> {
    for chunk in bytes.chunks(64) {
        class.write_packet(chunk).await?;
    }
    if bytes.len().is_multiple_of(64) && !bytes.is_empty() {
        // A full last packet needs a zero-length one to end the transfer.
        class.write_packet(&[]).await?;
    }
    Ok(())
}

async fn answer(line: &str, out: &mut String<2048>) {
    let armed = ARMED.load(Ordering::Relaxed);
    let mut guard = SETTINGS.lock().await;
    let Some((settings, _stored)) = guard.as_mut() else {
        let _ = out.push_str("settings not loaded yet\r\n");
        return;
    };
    let _ = match parse_line(line) {
        Ok(Command::Nothing) => Ok(()),
        Ok(Command::Help) => out.write_str(HELP),
        Ok(Command::List(prefix)) => write_list(out, settings, prefix),
        Ok(Command::Get(name)) => write_setting(out, settings, name),
        Ok(Command::Set { .. } | Command::SetAll(_) | Command::Save | Command::Defaults)
            if armed =>
        {
            out.write_str("refused: disarm first\r\n")
        }
        Ok(Command::Set { name, value }) => match settings.set_text(name, value) {
            Ok(()) => {
                SETTINGS_CHANGED.signal(());
                write_setting(out, settings, name)
            }
            Err(e) => writeln!(out, "{e}"),
        },
        Ok(Command::SetAll(pairs)) => match settings.set_text_pairs(pairs) {
            Ok(()) => {
                SETTINGS_CHANGED.signal(());
                out.write_str("ok\r\n")
            }
            Err(e) => writeln!(out, "{e}"),
        },
        Ok(Command::Save) => {
            SAVE_REQUEST.signal(());
            out.write_str("saving\r\n")
        }
        Ok(Command::Defaults) => {
            *settings = Settings::default();
            SETTINGS_CHANGED.signal(());
            out.write_str("factory values (not saved)\r\n")
        }
        Ok(Command::Status) => {
            let link_up = LINK_INPUT.lock(|c| c.get()).up;
            let _ = match FLIGHT_STATE.lock(|c| c.get()) {
                Some((state, blockers)) => writeln!(
                    out,
                    "mode {}, failsafe {}, link {}, arm blockers {:#x}, attitude {:?} deg",
                    state.mode.name(),
                    state.failsafe,
                    if link_up { "up" } else { "down" },
                    blockers,
                    state.attitude_deg
                ),
                None => writeln!(out, "flight loop not running (IMU?)"),
            };
            let battery = BATTERY.try_get();
            match battery {
                Some(b) => writeln!(
                    out,
                    "armed {armed}, battery {} mV {} mA {:?}",
                    b.voltage_mv, b.current_ma, b.level
                ),
                None => writeln!(out, "armed {armed}, battery unknown"),
            }
        }
        Err(e) => writeln!(out, "{e}"),
    };
}
