//! The PPM end-to-end path one rung lower: the module core drives the link master through
//! the driver's link adapter (`radio_rfm22b::link::LinkRadio`, what the firmware runs) on
//! the real `radio-rfm22b` driver over a virtual Si4432 (`si4432-sim`, register level); the
//! flight side runs the follower the same way on a second virtual chip.
//! Channels must arrive exactly; the flight battery must come back as S.Port VFAS and on the
//! HM-10 stream.

// Test helpers outside #[test] fns are not covered by clippy.toml's test allowances.
#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use common::{
    FLIGHT_EPOCH_US, FlightHooks, FlightSide, MODULE_EPOCH_US, ModuleHooks, flight_battery,
    module_settings,
};
use embedded_hal_async::delay::DelayNs;
use module_core::air::{AirLink, link_params};
use module_core::app::App;
use module_core::channels::us_to_ticks;
use module_core::handset::Handset;
use module_core::hm10::relay::MAX_FRAME_LEN;
use module_core::settings::{InputProtocol, OutputProtocol};
use radio_rfm22b::Rfm22b;
use radio_rfm22b::TxPower;
use radio_rfm22b::link::LinkRadio;
use si4432_sim::{RadioConfig as Placement, SimClock, Simulation};
use taulink_handset::sport::{self, value_id};
use telemetry::channels::FailsafeValues;
use telemetry::link::core::{Follower, Master};
use telemetry::link::follower::run_follower;
use telemetry::link::master::run_master;
use telemetry::messages::{Decoded, Message, MessageReader};

const WIDTHS_US: [u16; 8] = [1005, 1500, 1995, 1250, 1750, 1111, 1888, 1600];
const RUN_US: u64 = 2_000_000;

#[test]
fn ppm_over_the_driver_on_virtual_si4432s() {
    let settings = module_settings(InputProtocol::Ppm, OutputProtocol::SPort);
    let params = link_params(&settings).unwrap();
    let sim = Simulation::new(42);
    let medium = sim.medium();
    let module_chip = medium.add_radio(Placement::at([0.0, 0.0, 0.0]));
    let flight_chip = medium.add_radio(Placement::at([150.0, 0.0, 0.0]));

    let app = Rc::new(RefCell::new(
        App::new(settings, AirLink::new(), Handset::new(&settings), true).unwrap(),
    ));
    let mut module_clock = SimClock::new(medium.time(), MODULE_EPOCH_US, 0.0);
    let mut module_radio = LinkRadio::new(
        Rfm22b::new(
            module_chip.spi,
            module_chip.nirq,
            module_chip.sdn,
            module_chip.delay,
        ),
        TxPower::from_step(settings.tx_power),
    );
    let mut hooks = ModuleHooks { app: app.clone() };
    sim.spawn(async move {
        let mut master = Master::new(params);
        let result = run_master(
            &mut module_radio,
            &mut module_clock,
            &mut master,
            &mut hooks,
        );
        let Err(e) = result.await;
        panic!("module radio failed: {e:?}");
    });

    let flight = Rc::new(RefCell::new(FlightSide::default()));
    let mut flight_clock = SimClock::new(medium.time(), FLIGHT_EPOCH_US, 0.0);
    let mut flight_radio = LinkRadio::new(
        Rfm22b::new(
            flight_chip.spi,
            flight_chip.nirq,
            flight_chip.sdn,
            flight_chip.delay,
        ),
        TxPower::from_step(7),
    );
    let mut flight_hooks = FlightHooks {
        side: flight.clone(),
    };
    let mut boot_delay = sim.delay();
    sim.spawn(async move {
        boot_delay.delay_us(77_777).await;
        let mut follower = Follower::new(params, FailsafeValues::default(), 250_000);
        let _ = run_follower(
            &mut flight_radio,
            &mut flight_clock,
            &mut follower,
            &mut flight_hooks,
        )
        .await;
    });

    // The Taranis, the JR line (every 2 ms), the phone (every 10 ms) and the 10 Hz tick.
    let (ppm_app, ppm_medium, mut ppm_delay) = (app.clone(), medium.clone(), sim.delay());
    sim.spawn(async move {
        loop {
            for width in WIDTHS_US
                .iter()
                .map(|w| u32::from(*w))
                .chain([22_500 - 12_099])
            {
                let now = ppm_medium.now().as_micros() as u64 + MODULE_EPOCH_US;
                ppm_app.borrow_mut().on_ppm_edge(now as u32);
                ppm_delay.delay_us(width).await;
            }
        }
    });
    let sport_bytes = Rc::new(RefCell::new(Vec::new()));
    let phone_bytes = Rc::new(RefCell::new(Vec::new()));
    let (io_app, io_medium, mut io_delay) = (app.clone(), medium.clone(), sim.delay());
    let (sport_log, phone_log) = (sport_bytes.clone(), phone_bytes.clone());
    sim.spawn(async move {
        let mut k = 0u64;
        loop {
            io_delay.delay_us(2_000).await;
            k += 1;
            let now = io_medium.now().as_micros() as u64 + MODULE_EPOCH_US;
            let mut app = io_app.borrow_mut();
            let mut out = [0u8; 128];
            let n = app.next_handset_bytes(now, &mut out).len();
            sport_log.borrow_mut().extend_from_slice(&out[..n]);
            if k.is_multiple_of(5) {
                let mut frame = [0u8; MAX_FRAME_LEN];
                while let Some(n) = app.next_phone_frame(&mut frame) {
                    phone_log.borrow_mut().extend_from_slice(&frame[..n]);
                }
            }
            if k.is_multiple_of(50) {
                app.on_ppm_tick(now as u32);
                app.on_tick();
            }
        }
    });
    sim.run_for(Duration::from_micros(RUN_US));

    // The sum of the widths above is 12 099 µs; the rest period closes the 22.5 ms frame.
    assert_eq!(WIDTHS_US.iter().map(|&w| u32::from(w)).sum::<u32>(), 12_099);
    let flight = flight.borrow();
    let (_, output) = flight
        .outputs
        .last()
        .expect("the flight side heard the module");
    for (channel, &width) in WIDTHS_US.iter().enumerate() {
        assert_eq!(output[channel], us_to_ticks(width), "channel {channel}");
    }
    let after_lock = flight.outputs.iter().filter(|(t, _)| *t > 500_000).count();
    assert!(after_lock > 200, "{after_lock} uplinks in 1.5 s");

    let mut decoder = sport::Decoder::new();
    let mut vfas = Vec::new();
    decoder.push_all(&sport_bytes.borrow(), |event| {
        if let sport::Event::Frame(frame) = event
            && frame.value_id == value_id::VFAS
        {
            vfas.push(frame.value);
        }
    });
    assert!(!vfas.is_empty());
    assert!(vfas.iter().all(|&v| v == 1187));

    let mut reader = MessageReader::new();
    let mut batteries = 0;
    for &b in phone_bytes.borrow().iter() {
        match reader.push(b) {
            Some(Decoded::Message(Message::Battery(battery))) => {
                assert_eq!(battery, flight_battery());
                batteries += 1;
            }
            Some(Decoded::Dropped) => panic!("phone frame dropped"),
            _ => {}
        }
    }
    assert!(
        batteries >= 10,
        "{batteries} battery messages on the HM-10 side"
    );
    eprintln!(
        "chip level: {} uplinks, {} VFAS frames, {batteries} battery messages to the phone",
        flight.outputs.len(),
        vfas.len()
    );
}
