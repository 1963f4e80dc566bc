//! The 433.05–434.79 MHz ISM plan end to end: a module bound on it at every rate mode flies
//! its channels to a flight side over the mock air, and every packet the master sends is
//! inside the sub-band (the radio configuration's grid, checked against the occupied
//! bandwidth of each mode).

#![allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]

mod common;

use common::World;
use module_core::air::link_params;
use module_core::settings::{Band, InputProtocol, OutputProtocol, RateMode};
use telemetry::link::hopping::HOP_CHANNELS;

#[test]
fn every_rate_mode_runs_inside_the_ism_sub_band() {
    for rate in RateMode::ALL {
        let settings = module_core::settings::Settings {
            band: Band::Ism433,
            rate,
            ..common::module_settings(InputProtocol::Ppm, OutputProtocol::SPort)
        };
        let config = link_params(&settings).unwrap().radio_config();
        let deviation = radio_rfm22b::link::modem_for(rate).unwrap().deviation_hz();
        let half_occupied = deviation + rate.bit_rate_bps() / 2;
        let last = config.channel_hz(HOP_CHANNELS as u8 - 1);
        assert!(
            config.channel_hz(0) - half_occupied >= 433_050_000,
            "{rate:?}"
        );
        assert!(last + half_occupied <= 434_790_000, "{rate:?}");

        let mut world = World::new(settings);
        // PPM: 8 channels, EdgeTX style, for 1.5 s.
        let widths = [1000u16, 1200, 1400, 1500, 1600, 1800, 2000, 1500];
        let app = world.app.clone();
        let time = world.time.clone();
        world.executor.spawn(async move {
            let mut t = 0u64;
            while t < 1_500_000 {
                let mut edge = t;
                for w in widths {
                    time.sleep_until(edge).await;
                    app.borrow_mut()
                        .on_ppm_edge(common::module_now(edge) as u32);
                    edge += u64::from(w);
                }
                time.sleep_until(edge).await;
                app.borrow_mut()
                    .on_ppm_edge(common::module_now(edge) as u32);
                t += 22_500;
            }
        });
        world.run_until(1_500_000);
        let flight = world.flight.borrow();
        let (_, last_out) = flight.outputs.last().expect("channels arrived");
        for (i, w) in widths.iter().enumerate() {
            let us = module_core::channels::ticks_to_us(last_out[i]);
            assert!(us.abs_diff(*w) <= 1, "{rate:?} ch{i}: {us}");
        }
    }
}
