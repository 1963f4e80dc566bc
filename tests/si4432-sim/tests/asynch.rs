//! Async use in virtual time: nIRQ waits raced against delays (the driver's timeout
//! pattern), dropped waits, a two-task ping-pong, and determinism of the whole trace.
#![allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]

mod common;

use common::*;
use core::time::Duration;
use embassy_futures::select::{Either, select};
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use si4432_sim::{Medium, MediumConfig, Outcome, RadioConfig, RadioHandle, Simulation, TraceFrame};

/// Wait for nIRQ, at most `timeout_us`; true if it went low.
async fn irq_or_timeout(r: &mut RadioHandle, timeout_us: u32) -> bool {
    matches!(
        select(r.nirq.wait_for_low(), r.delay.delay_us(timeout_us)).await,
        Either::First(_)
    )
}

async fn send(r: &mut RadioHandle, data: &[u8]) -> bool {
    awrite(&mut r.spi, 0x07, &[0x02]).await;
    awrite(&mut r.spi, 0x08, &[0x03]).await;
    awrite(&mut r.spi, 0x08, &[0x00]).await;
    awrite(&mut r.spi, 0x3E, &[data.len() as u8]).await;
    awrite(&mut r.spi, 0x7F, data).await;
    astatus(&mut r.spi).await;
    awrite(&mut r.spi, 0x05, &[0x04, 0x00]).await;
    awrite(&mut r.spi, 0x07, &[0x0A]).await;
    while irq_or_timeout(r, 20_000).await {
        if astatus(&mut r.spi).await.0 & 0x04 != 0 {
            return true;
        }
    }
    false
}

async fn receive(r: &mut RadioHandle, medium: &Medium, timeout: Duration) -> Option<Vec<u8>> {
    let deadline = medium.now() + timeout;
    awrite(&mut r.spi, 0x07, &[0x02]).await;
    awrite(&mut r.spi, 0x08, &[0x03]).await;
    awrite(&mut r.spi, 0x08, &[0x00]).await;
    astatus(&mut r.spi).await;
    awrite(&mut r.spi, 0x05, &[0x03, 0x00]).await; // ipkvalid | icrcerror
    awrite(&mut r.spi, 0x07, &[0x06]).await;
    loop {
        let left = deadline.saturating_sub(medium.now());
        if left.is_zero() || !irq_or_timeout(r, left.as_micros() as u32).await {
            awrite(&mut r.spi, 0x07, &[0x02]).await;
            return None;
        }
        let (s1, _) = astatus(&mut r.spi).await;
        if s1 & 0x02 != 0 {
            let len = aread_n(&mut r.spi, 0x4B, 1).await[0] as usize;
            return Some(aread_n(&mut r.spi, 0x7F, len).await);
        }
        if s1 & 0x01 != 0 {
            awrite(&mut r.spi, 0x08, &[0x02]).await; // CRC error: flush, keep listening
            awrite(&mut r.spi, 0x08, &[0x00]).await;
        }
    }
}

#[test]
fn timeout_wins_when_nothing_happens_and_irq_wins_at_the_exact_moment() {
    let sim = Simulation::new(5);
    let medium = sim.medium();
    let mut a = medium.add_radio(RadioConfig::default());
    configure_57600(&mut a.spi, true);
    let m = medium.clone();
    let task = sim.spawn(async move {
        astatus(&mut a.spi).await;
        let t0 = m.now();
        let fired = irq_or_timeout(&mut a, 1_000).await;
        let t_timeout = m.now() - t0;
        // The dropped wait left a waker behind; the next wait must still work.
        awrite(&mut a.spi, 0x3E, &[16]).await;
        awrite(&mut a.spi, 0x7F, &[0x42; 16]).await;
        awrite(&mut a.spi, 0x05, &[0x04]).await;
        let t1 = m.now();
        awrite(&mut a.spi, 0x07, &[0x09]).await;
        let sent = irq_or_timeout(&mut a, 50_000).await;
        let t_sent = m.now() - t1;
        let (s1, _) = astatus(&mut a.spi).await;
        (fired, t_timeout, sent, t_sent, s1)
    });
    sim.run_for(Duration::from_millis(100));
    let (fired, t_timeout, sent, t_sent, s1) = task.take().unwrap();
    assert!(!fired);
    assert_eq!(t_timeout, Duration::from_millis(1));
    assert!(sent);
    // The 2-byte txon write on the 5.25 MHz bus (3 µs overhead + 16 bits), 200 µs PLL
    // settle, 264 bits (6+4+4+1+16+2 bytes) at 57 601.93 bit/s, then the 5 µs nIRQ latency.
    let spi = si4432_sim::SPI_OVERHEAD_NS + (16_000_000_000u64).div_ceil(5_250_000);
    assert_eq!(
        t_sent,
        Duration::from_nanos(spi + 200_000 + 4_583_180 + si4432_sim::IRQ_LATENCY_NS)
    );
    assert_eq!(s1, 0x04);
}

/// Master sends every 20 ms and waits for a reply; follower answers every packet.
fn ping_pong(seed: u64, loss: f64, rounds: usize) -> (Vec<TraceFrame>, usize, usize) {
    let config = MediumConfig {
        packet_loss: loss,
        ..MediumConfig::default()
    };
    let sim = Simulation::with_config(seed, config);
    let medium = sim.medium();
    let mut master = medium.add_radio(RadioConfig::at([0.0, 0.0, 0.0]));
    let mut follower = medium.add_radio(RadioConfig::at([300.0, 0.0, 0.0]));
    configure_57600(&mut master.spi, true);
    configure_57600(&mut follower.spi, true);
    let m = medium.clone();
    let master_task = sim.spawn(async move {
        let mut replies = 0;
        for i in 0..rounds {
            let slot_start = m.now();
            assert!(send(&mut master, &[i as u8; 12]).await);
            if let Some(reply) = receive(&mut master, &m, Duration::from_millis(12)).await {
                assert_eq!(reply, vec![!(i as u8); 6]);
                replies += 1;
            }
            let used = m.now() - slot_start;
            master
                .delay
                .delay_ns((Duration::from_millis(20) - used).as_nanos() as u32)
                .await;
        }
        replies
    });
    let m = medium.clone();
    let follower_task = sim.spawn(async move {
        let mut heard = 0;
        loop {
            if let Some(packet) = receive(&mut follower, &m, Duration::from_millis(100)).await {
                heard += 1;
                send(&mut follower, &[!packet[0]; 6]).await;
            } else {
                return heard;
            }
        }
    });
    sim.run_until_or(Duration::from_secs(60), || {
        master_task.is_finished() && follower_task.is_finished()
    });
    (
        medium.trace(),
        master_task.take().unwrap(),
        follower_task.take().unwrap(),
    )
}

#[test]
fn ping_pong_between_two_async_tasks() {
    let (trace, replies, heard) = ping_pong(1, 0.0, 50);
    assert_eq!(heard, 50);
    assert_eq!(replies, 50);
    assert_eq!(trace.len(), 100);
    // Uplink frames start every 20 ms exactly (settle included), downlinks in between.
    assert_eq!(trace[2].start - trace[0].start, Duration::from_millis(20));
    assert!(trace.iter().all(|f| matches!(
        f.receptions[0].outcome,
        Outcome::Delivered { bit_errors: 0 }
    )));
}

#[test]
fn same_seed_same_trace_different_seed_different_trace() {
    let (a, ra, ha) = ping_pong(42, 0.3, 60);
    let (b, rb, hb) = ping_pong(42, 0.3, 60);
    assert_eq!(a, b);
    assert_eq!((ra, ha), (rb, hb));
    // 30 % loss each way: some but not all rounds complete.
    assert!(ra > 10 && ra < 50, "{ra}");
    let (c, _, _) = ping_pong(43, 0.3, 60);
    assert_ne!(a, c);
}

#[test]
fn sdn_power_cycle_gives_a_falling_edge_at_the_end_of_the_power_on_reset() {
    use embedded_hal::digital::OutputPin;
    let sim = Simulation::new(8);
    let medium = sim.medium();
    let mut r = medium.add_radio(RadioConfig::default());
    let m = medium.clone();
    let task = sim.spawn(async move {
        astatus(&mut r.spi).await;
        r.sdn.set_high().unwrap();
        r.delay.delay_ms(10).await;
        r.sdn.set_low().unwrap();
        let t0 = m.now();
        r.nirq.wait_for_falling_edge().await.unwrap();
        let t_por = m.now() - t0;
        let first = astatus(&mut r.spi).await;
        r.nirq.wait_for_falling_edge().await.unwrap();
        let t_ready = m.now() - t0;
        let second = astatus(&mut r.spi).await;
        (t_por, first, t_ready, second)
    });
    sim.run_for(Duration::from_millis(50));
    let (t_por, first, t_ready, second) = task.take().unwrap();
    // Each edge reaches the task after the nIRQ latency.
    let latency = Duration::from_nanos(si4432_sim::IRQ_LATENCY_NS);
    assert_eq!(t_por, Duration::from_millis(15) + latency);
    assert_eq!(first, (0x00, 0x01));
    assert_eq!(t_ready, Duration::from_micros(15_600) + latency);
    assert_eq!(second, (0x00, 0x02));
}
