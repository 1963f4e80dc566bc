//! The USB CDC console (VID/PID 0x20A0/0x415B as Tau Labs used): reads lines, hands each
//! to `FlightApp::on_console_line` (the command language and its refusals live there),
//! sends the answer back.

use embassy_futures::join::join;
use embassy_stm32::peripherals::USB_OTG_FS;
use embassy_stm32::usb::Driver;
use embassy_usb::class::cdc_acm::{CdcAcmClass, State};
use embassy_usb::driver::EndpointError;
use embassy_usb::{Builder, Config};
use flight_app::settings::LineAssembler;
use heapless::String;
use static_cell::StaticCell;

use crate::firmware::shared::with_app;
use crate::firmware::usb_cdc::{Reply, send};

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
            // A host has the console: arming is refused until it goes
            // (`flight_app::supervisor::Inputs::usb_connected`).
            with_app(|a| a.on_usb(true));
            // A disconnect ends the session; wait for the next one.
            let _ = serve(&mut class).await;
            with_app(|a| a.on_usb(false));
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
            let mut reply = Reply(String::new());
            with_app(|a| a.on_console_input(line.as_ref().map(|l| l.as_str()), &mut reply));
            send(class, reply.0.as_bytes()).await?;
        }
    }
}
