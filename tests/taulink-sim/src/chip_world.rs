//! The chip-level world: both link ends run the real `radio-rfm22b` driver on virtual
//! Si4432s (`si4432-sim`), register by register, through its RF medium and executor.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use radio_rfm22b::{Rfm22b, TxPower};
use si4432_sim::{
    Interference, Medium, Outcome as ChipOutcome, RadioConfig as ChipPlacement, RadioId, Simulation,
};
use telemetry::link::rate::airtime_us;
use telemetry::link::{HOP_CHANNELS, LinkParams};
use telemetry::mock::{MediumStats, SplitMix64};

use crate::attack::{Powered, Witnessed, attacker, flight_end_powered, power_plan, victim_of};
use crate::driver::{LinkRadio, SimClock};
use crate::ends::{FlightStart, ModuleBind, apps, flight_end, master_nonce_seed, module_end};
use crate::probe::{Now, Record, Shared, Witness};
use crate::scenario::Scenario;
use crate::world::{
    FLIGHT_EPOCH_US, MODULE_EPOCH_US, Outcome, STATUS_PERIOD_US, Status, StatusTracker, params_for,
};

#[allow(clippy::too_many_arguments)]
fn spawn_pair(
    sim: &Simulation,
    medium: &Medium,
    s: &Scenario,
    params: LinkParams,
    x_m: (f64, f64),
    salt: u64,
    bind: bool,
    attacker: Option<RadioId>,
) -> (Shared, RadioId, RadioId) {
    let record: Shared = Rc::new(RefCell::new(Record::default()));
    // Crystals a few ppm off, in opposite directions: AFC and frequency tolerance at work.
    let placement = |x: f64, ppm: f64| {
        let mut p = ChipPlacement::at([x, 0.0, 0.0]);
        p.crystal_error_ppm = ppm;
        p
    };
    let module = medium.add_radio(placement(x_m.0, 8.0));
    let flight = medium.add_radio(placement(x_m.1, -6.0));
    let ids = (module.id, flight.id);
    let flight_chip = flight.chip.clone();
    // The MCU clocks drift too, 40 ppm apart: the follower must keep re-timing its grid.
    let module_clock = SimClock::new(medium.time(), MODULE_EPOCH_US, 20.0);
    let flight_clock = SimClock::new(medium.time(), FLIGHT_EPOCH_US, -20.0);
    let link_radio = |radio| {
        let r = LinkRadio::new(radio, TxPower::MAX);
        if s.header_check {
            r
        } else {
            r.without_header_check()
        }
    };
    // Under attack, each end's radio notes who sent what it delivered, so the hooks can
    // attribute the frames their core accepted.
    let witnessed = |radio, id| Witnessed::new(radio, medium.clone(), id, attacker.is_some());
    let module_radio = witnessed(
        link_radio(Rfm22b::new(
            module.spi,
            module.nirq,
            module.sdn,
            module.delay,
        )),
        ids.0,
    );
    let flight_radio = witnessed(
        link_radio(Rfm22b::new(
            flight.spi,
            flight.nirq,
            flight.sdn,
            flight.delay,
        )),
        ids.1,
    );
    let m = medium.clone();
    let now: Now = Rc::new(move || m.now().as_micros() as u64);
    let (mut module_app, mut flight_app) = apps(s, now, &record, salt);
    if let Some(attacker) = attacker {
        module_app.witness = Some(Witness::new(module_radio.last_sender(), attacker));
        flight_app.witness = Some(Witness::new(flight_radio.last_sender(), attacker));
    }
    sim.spawn(module_end(
        module_radio,
        module_clock,
        params,
        bind.then(|| ModuleBind::of(s, salt)),
        s.key.map(|k| (k, master_nonce_seed(s.seed, salt))),
        module_app,
    ));
    let start = FlightStart::of(s, bind, params, salt);
    let plan = s
        .attack
        .map(|a| power_plan(a, s.duration_s))
        .unwrap_or_default();
    if attacker.is_some() && !plan.is_empty() {
        let power = Powered {
            medium: medium.clone(),
            delay: sim.delay(),
            chip: flight_chip,
            plan,
            module_params: params,
        };
        sim.spawn(flight_end_powered(
            flight_radio,
            flight_clock,
            start,
            flight_app,
            record.clone(),
            power,
        ));
    } else {
        sim.spawn(flight_end(
            flight_radio,
            flight_clock,
            start,
            flight_app,
            record.clone(),
            SimClock::virtual_us,
        ));
    }
    (record, ids.0, ids.1)
}

/// Random interference bursts over the link's grid at `duty` of the time.
fn add_interference(medium: &Medium, s: &Scenario, params: &LinkParams) {
    let mut rng = SplitMix64::new(s.seed ^ 0x1A33_E500);
    let duty = s.interference.clamp(0.001, 0.95);
    let on_us = u64::from(airtime_us(32, s.rate.bit_rate_bps()));
    let end_us = (s.duration_s * 1e6) as u64;
    let mut t = 0u64;
    while t < end_us {
        let channel = rng.below(HOP_CHANNELS as u64) as u8;
        medium.add_interference(Interference {
            start: Duration::from_micros(t),
            end: Duration::from_micros(t + on_us),
            center_hz: f64::from(params.band.channel_hz(channel)),
            bandwidth_hz: 2.0 * f64::from(s.rate.bit_rate_bps()),
            power_dbm: -60.0,
        });
        t += on_us + (on_us as f64 * (1.0 - duty) / duty * 2.0 * rng.unit()) as u64;
    }
}

fn air_stats(medium: &Medium) -> MediumStats {
    medium.with_trace(|frames| {
        let mut st = MediumStats {
            transmitted: frames.len() as u64,
            ..MediumStats::default()
        };
        for r in frames.iter().flat_map(|f| f.receptions.iter()) {
            match r.outcome {
                ChipOutcome::Delivered { .. } => st.delivered += 1,
                ChipOutcome::CrcError { .. } => st.chip_crc_rejected += 1,
                ChipOutcome::HeaderMismatch => st.header_rejected += 1,
                ChipOutcome::RandomLoss => st.lost_random += 1,
                ChipOutcome::TooWeak => st.lost_weak += 1,
                ChipOutcome::Captured => st.lost_collision += 1,
                _ => {}
            }
        }
        st
    })
}

fn accumulate(total: &mut MediumStats, part: MediumStats) {
    total.transmitted += part.transmitted;
    total.delivered += part.delivered;
    total.lost_weak += part.lost_weak;
    total.lost_collision += part.lost_collision;
    total.lost_random += part.lost_random;
    total.lost_cut += part.lost_cut;
    total.header_rejected += part.header_rejected;
    total.chip_crc_rejected += part.chip_crc_rejected;
    total.corrupted_delivered += part.corrupted_delivered;
}

/// Runs `s` on the chip simulator, calling `status` once per virtual second.
pub fn simulate_chip(s: &Scenario, mut status: impl FnMut(&Status)) -> Outcome {
    let sim = Simulation::new(s.seed);
    let medium = sim.medium();
    medium.set_packet_loss(s.loss);
    let mut rng = SplitMix64::new(s.seed);
    let params = params_for(s, rng.next_u64() as u32);
    // The attacker, when there is one, a tenth of the link's length from the end it
    // targets, so its frames win there (at the other end it is about as loud as that end).
    let attacker_radio = s
        .attack
        .map(|a| medium.add_radio(ChipPlacement::at([a.position() * s.distance_m, 0.0, 0.0])));
    let (main, module_id, flight_id) = spawn_pair(
        &sim,
        &medium,
        s,
        params,
        (0.0, s.distance_m),
        0xA11CE,
        s.bind,
        attacker_radio.as_ref().map(|r| r.id),
    );
    if let (Some(attack), Some(r), false) = (s.attack, attacker_radio, s.silent_attacker) {
        let victim = victim_of(s, &params);
        let clock = SimClock::new(medium.time(), 0, 0.0);
        let radio = LinkRadio::new(Rfm22b::new(r.spi, r.nirq, r.sdn, r.delay), TxPower::MAX);
        let dictionary = crate::attack::guess::dictionary(s.phrase.as_deref());
        sim.spawn(attacker(
            attack,
            radio,
            clock,
            victim,
            main.clone(),
            s.seed,
            dictionary,
        ));
    }
    let foreign = s.foreign_link.then(|| {
        let foreign_params = params_for(s, rng.next_u64() as u32);
        let mid = s.distance_m / 2.0;
        spawn_pair(
            &sim,
            &medium,
            s,
            foreign_params,
            (mid - 5.0, mid + 5.0),
            0xB0B,
            false,
            None,
        )
        .0
    });
    if s.interference > 0.0 {
        add_interference(&medium, s, &params);
    }
    if let Some((from_s, to_s)) = s.cut_s {
        let (m, delay) = (medium.clone(), sim.delay());
        sim.spawn(async move {
            delay.sleep_ns((from_s * 1e9) as u64).await;
            m.set_attenuation(module_id, flight_id, 300.0);
            delay.sleep_ns(((to_s - from_s) * 1e9) as u64).await;
            m.set_attenuation(module_id, flight_id, 0.0);
        });
    }
    let end_us = (s.duration_s * 1e6) as u64;
    let mut tracker = StatusTracker::default();
    let mut air = MediumStats::default();
    let mut t_us = 0;
    while t_us < end_us {
        let step = STATUS_PERIOD_US.min(end_us - t_us);
        sim.run_for(Duration::from_micros(step));
        t_us += step;
        status(&tracker.sample(t_us, &main.borrow(), step));
        // The trace grows with every frame; keep only what the summary needs.
        if medium.trace_len() > 50_000 {
            accumulate(&mut air, air_stats(&medium));
            medium.clear_trace();
        }
    }
    accumulate(&mut air, air_stats(&medium));
    let main_record = main.borrow().clone();
    Outcome {
        main: main_record,
        foreign: foreign.map(|f| f.borrow().clone()),
        medium: air,
        params,
    }
}
