//! Throughput of the simulation: two ends, each sending 500 packets/s for 30 s of virtual
//! time at 256 kbit/s (master packet, follower reply, every 2 ms), driven through the async
//! embedded-hal endpoints with raw register writes and nIRQ waits raced against timeouts.
//!
//! `cargo run --release -p si4432-sim --example ping_pong [seconds] [loss]`
#![allow(
    clippy::unwrap_used,
    clippy::indexing_slicing,
    clippy::panic,
    clippy::expect_used
)]

use core::time::Duration;
use std::time::Instant;

use embassy_futures::select::{Either, select};
use embedded_hal::spi::Operation;
use embedded_hal_async::delay::DelayNs;
use embedded_hal_async::digital::Wait;
use embedded_hal_async::spi::SpiDevice;
use si4432_sim::{Medium, MediumConfig, Outcome, RadioConfig, RadioHandle, Simulation};

async fn write(r: &mut RadioHandle, address: u8, data: &[u8]) {
    r.spi
        .transaction(&mut [Operation::Write(&[address | 0x80]), Operation::Write(data)])
        .await
        .unwrap();
}

async fn read(r: &mut RadioHandle, address: u8, buf: &mut [u8]) {
    r.spi
        .transaction(&mut [Operation::Write(&[address]), Operation::Read(buf)])
        .await
        .unwrap();
}

async fn status(r: &mut RadioHandle) -> u8 {
    let mut s = [0u8; 2];
    read(r, 0x03, &mut s).await;
    s[0]
}

/// 256 kbit/s GFSK with 150 kHz deviation (Tau Labs' 256k row with the deviation fixed),
/// 433.92 MHz, 4-byte preamble, sync 2D D4, no header, variable length, CRC-16.
async fn configure(r: &mut RadioHandle) {
    status(r).await;
    write(r, 0x05, &[0, 0]).await;
    for (a, v) in [
        (0x1Cu8, 0x8Du8),
        (0x1D, 0x40),
        (0x1E, 0x02),
        (0x20, 0x2F),
        (0x21, 0x02),
        (0x22, 0xBB),
        (0x23, 0x0D),
        (0x24, 0x07),
        (0x25, 0xFF),
        (0x2A, 0x50),
        (0x6E, 0x41),
        (0x6F, 0x89),
        (0x70, 0x0C),
        (0x71, 0x23),
        (0x72, 0xF0),
        (0x30, 0x8D),
        (0x32, 0x00),
        (0x33, 0x02),
        (0x34, 0x08),
        (0x35, 0x28),
        (0x6D, 0x0F),
        (0x75, 0x53),
        (0x76, 0x64),
        (0x77, 0x00),
    ] {
        write(r, a, &[v]).await;
    }
}

async fn send(r: &mut RadioHandle, data: &[u8]) -> bool {
    write(r, 0x07, &[0x01]).await;
    write(r, 0x08, &[0x01]).await;
    write(r, 0x08, &[0x00]).await;
    write(r, 0x3E, &[data.len() as u8]).await;
    write(r, 0x7F, data).await;
    status(r).await;
    write(r, 0x05, &[0x04]).await;
    write(r, 0x07, &[0x09]).await;
    loop {
        match select(r.nirq.wait_for_low(), r.delay.delay_us(5_000)).await {
            Either::First(_) if status(r).await & 0x04 != 0 => return true,
            Either::First(_) => {}
            Either::Second(()) => return false,
        }
    }
}

async fn receive(
    r: &mut RadioHandle,
    medium: &Medium,
    timeout: Duration,
    buf: &mut [u8],
) -> Option<usize> {
    let deadline = medium.now() + timeout;
    write(r, 0x08, &[0x02]).await;
    write(r, 0x08, &[0x00]).await;
    status(r).await;
    write(r, 0x05, &[0x03]).await;
    write(r, 0x07, &[0x05]).await;
    loop {
        let left = deadline.saturating_sub(medium.now());
        let woke = !left.is_zero()
            && matches!(
                select(
                    r.nirq.wait_for_low(),
                    r.delay.delay_ns(left.as_nanos() as u32)
                )
                .await,
                Either::First(_)
            );
        if !woke {
            write(r, 0x07, &[0x01]).await;
            return None;
        }
        let s = status(r).await;
        if s & 0x02 != 0 {
            let mut len = [0u8];
            read(r, 0x4B, &mut len).await;
            let n = usize::from(len[0]).min(buf.len());
            read(r, 0x7F, &mut buf[..n]).await;
            return Some(n);
        }
        if s & 0x01 != 0 {
            write(r, 0x08, &[0x02]).await;
            write(r, 0x08, &[0x00]).await;
        }
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let seconds: u64 = args.next().map_or(30, |s| s.parse().expect("seconds"));
    let loss: f64 = args.next().map_or(0.0, |s| s.parse().expect("loss"));
    let config = MediumConfig {
        packet_loss: loss,
        ..MediumConfig::default()
    };
    let sim = Simulation::with_config(2024, config);
    let medium = sim.medium();
    let mut master = medium.add_radio(RadioConfig::at([0.0, 0.0, 0.0]));
    let mut follower = medium.add_radio(RadioConfig::at([500.0, 0.0, 0.0]));
    let slots = seconds * 500;

    let m = medium.clone();
    let master_task = sim.spawn(async move {
        configure(&mut master).await;
        let mut replies = 0u64;
        let mut buf = [0u8; 64];
        for i in 0..slots {
            let slot_end = Duration::from_millis(10) + Duration::from_micros(2_000 * i);
            send(&mut master, &[i as u8; 8]).await;
            let left = slot_end.saturating_sub(m.now() + Duration::from_micros(100));
            if receive(&mut master, &m, left, &mut buf).await.is_some() {
                replies += 1;
            }
            let wait = slot_end.saturating_sub(m.now());
            master.delay.delay_ns(wait.as_nanos() as u32).await;
        }
        replies
    });
    let m = medium.clone();
    let follower_task = sim.spawn(async move {
        configure(&mut follower).await;
        let mut heard = 0u64;
        let mut buf = [0u8; 64];
        while let Some(n) = receive(&mut follower, &m, Duration::from_millis(100), &mut buf).await {
            heard += 1;
            let reply: Vec<u8> = buf[..n].iter().map(|b| !b).collect();
            send(&mut follower, &reply).await;
        }
        heard
    });

    let host = Instant::now();
    sim.run_until_or(Duration::from_secs(seconds + 1), || {
        master_task.is_finished() && follower_task.is_finished()
    });
    let elapsed = host.elapsed();
    let replies = master_task.take().unwrap_or(0);
    let heard = follower_task.take().unwrap_or(0);
    let (frames, delivered) = medium.with_trace(|t| {
        (
            t.len(),
            t.iter()
                .filter(|f| {
                    f.receptions
                        .iter()
                        .any(|r| matches!(r.outcome, Outcome::Delivered { .. }))
                })
                .count(),
        )
    });
    println!("virtual time      {:.3} s", sim.now().as_secs_f64());
    println!("host time         {:.3} s", elapsed.as_secs_f64());
    println!(
        "speed-up          {:.1}×",
        sim.now().as_secs_f64() / elapsed.as_secs_f64()
    );
    println!("master packets    {slots}, follower heard {heard}, replies back {replies}");
    println!("frames on air     {frames}, delivered {delivered}");
    println!(
        "host per frame    {:.2} µs",
        elapsed.as_secs_f64() * 1e6 / frames.max(1) as f64
    );
}
