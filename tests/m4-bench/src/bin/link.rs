//! Per-slot work of both link ends, `telemetry::link::core::{Master, Follower}` — the sans-IO
//! state machines every slot runs on the module (master, nRF52840) and the flight board
//! (follower, STM32F405), both Cortex-M4F, so one thumbv7em count serves both MCUs' code
//! paths. F500, 16 channels, 1:4 telemetry, both telemetry streams kept full and the sticks
//! changing every slot (the worst case: every frame carries a full stream chunk and fresh
//! channels). The radio is left out (`radio` bench: driver work and SPI time per frame).
//!
//! The follower first acquires the master (not measured), then the pair runs `SLOTS` slots.
//! Each slot is five m4count regions, in this order:
//! 1. master `uplink_len` and `plan` (hop, schedule, frame build: channels, stream chunk,
//!    CRC — the length is counted before the radio is started, the frame built once with
//!    the channels latched, as `link::master::run_master` does);
//! 2. follower `plan` (hop, schedule; on a downlink slot its frame build);
//! 3. master completion: `on_sent`, or `on_received` of the downlink (frame parse, CRC,
//!    stream ack/reassembly, link quality) and `finish_listen`;
//! 4. follower completion: `on_received` of the uplink (frame parse, channels, stream), or
//!    `on_sent`;
//! 5. setup for the next slot (stream top-up, new sticks), not part of either end.
//!
//! Master per slot = regions 1 + 3, follower = 2 + 4. Each region also holds the ≈ 5
//! instructions of the marker call. The summary command is in `tests/m4-bench/README.md`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use core::hint::black_box;
    use m4_bench::{exit, m4count_marker};
    use telemetry::channels::{ChannelFormat, Channels, FailsafeValues};
    use telemetry::link::core::{Follower, Master, Step};
    use telemetry::link::{Band, LinkParams, LinkRx, RateMode};

    /// Slots measured: two hop cycles and a bit, so every slot kind and channel appears.
    const SLOTS: u32 = 80;
    /// Failsafe delay of the follower, µs (the firmware's default order of magnitude).
    const FAILSAFE_US: u64 = 1_000_000;

    let params = LinkParams::new(
        0xC0FF_EE11,
        Band::Mhz433,
        RateMode::F500,
        ChannelFormat::Full16,
        4,
    );
    let mut master = Master::new(params);
    let mut follower = Follower::new(params, FailsafeValues::default(), FAILSAFE_US);
    let slot_us = u64::from(master.schedule().slot_us());
    let mut sticks: Channels = core::array::from_fn(|i| 1000 + 37 * i as u16);
    master.set_channels(&sticks);
    let payload = [0xA5u8; 64];
    let top_up = |m: &mut Master, f: &mut Follower| {
        while m.uplink_stream.write(&payload) > 0 {}
        while f.downlink_stream.write(&payload) > 0 {}
    };
    top_up(&mut master, &mut follower);

    // Acquisition: the follower dwells on one channel; run the master until it sends there.
    let (mut mbuf, mut fbuf) = ([0u8; 64], [0u8; 64]);
    let Step::Listen { channel, .. } = follower.plan(0, &mut fbuf) else {
        exit()
    };
    let mut t = 0u64;
    let mut acquired = false;
    for _ in 0..1000 {
        let start = t;
        t += slot_us;
        match master.plan(start, &mut mbuf) {
            Step::Transmit {
                channel: c, len, ..
            } => {
                master.on_sent();
                if c == channel {
                    let end = start + u64::from(master.schedule().packet_end_offset_us(len));
                    let frame = mbuf.get(..len).unwrap_or(&[]);
                    follower.on_received(LinkRx::Packet { len, rssi_dbm: -70 }, frame, end);
                    acquired = true;
                    break;
                }
            }
            _ => master.finish_listen(),
        }
    }
    if !acquired || follower.in_failsafe() {
        fail()
    }

    let mut sent = sticks;
    let mut uplinks = 0u32;
    let mut downlinks = 0u32;
    for _ in 0..SLOTS {
        let now = black_box(t);
        m4count_marker();
        let _ = master.uplink_len();
        let m = master.plan(now, &mut mbuf);
        m4count_marker();
        let f = follower.plan(now, &mut fbuf);
        m4count_marker();
        match (m, f) {
            (Step::Transmit { len, .. }, Step::Listen { .. }) => {
                let end = now + u64::from(master.schedule().packet_end_offset_us(len));
                master.on_sent();
                m4count_marker();
                let frame = mbuf.get(..len).unwrap_or(&[]);
                follower.on_received(LinkRx::Packet { len, rssi_dbm: -70 }, frame, end);
                sent = sticks;
                uplinks += 1;
            }
            (Step::Listen { .. }, Step::Transmit { len, .. }) => {
                let end = now + u64::from(master.schedule().packet_end_offset_us(len));
                let frame = fbuf.get(..len).unwrap_or(&[]);
                let taken = master.on_received(LinkRx::Packet { len, rssi_dbm: -75 }, frame, end);
                master.finish_listen();
                m4count_marker();
                follower.on_sent();
                if !taken {
                    fail()
                }
                downlinks += 1;
            }
            _ => fail(),
        }
        m4count_marker();
        // Setup (region 5): keep both streams full, drain what arrived, move the sticks.
        let mut sink = [0u8; 64];
        while master.downlink_stream.read(&mut sink) > 0 {}
        while follower.uplink_stream.read(&mut sink) > 0 {}
        top_up(&mut master, &mut follower);
        for (i, s) in sticks.iter_mut().enumerate() {
            *s = 1000 + ((*s as usize + 7 * i + 3) % 1000) as u16;
        }
        master.set_channels(&sticks);
        t += slot_us;
    }
    m4count_marker();
    if follower.in_failsafe() || uplinks == 0 || downlinks == 0 || follower.output() != &sent {
        fail()
    }
    exit()
}

#[cfg(target_os = "none")]
fn fail() -> ! {
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}

#[cfg(not(target_os = "none"))]
fn main() {}
