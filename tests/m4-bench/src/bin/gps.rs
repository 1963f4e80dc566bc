//! Instruction counts of the GPS path: the UBX parser over one 100-byte NAV-PVT frame and
//! its decoding (region 1), and `GpsAiding::fuse` — quality checks, NED from home, latency
//! compensation and the position and velocity updates (region 2). The frame is the
//! ubxlib capture used in the `ubx` crate's transcript tests.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use core::hint::black_box;
    use flight_app::estimation::ins::aiding::AidingConfig;
    use flight_app::estimation::ins::aiding::gps::{GpsAiding, GpsAidingConfig};
    use flight_app::estimation::ins::{Config, Ins};
    use flight_app::sensors::ubx::{Message, Parser};
    use m4_bench::{exit, m4count_marker};

    const FRAME: [u8; 100] = [
        0xb5, 0x62, 0x01, 0x07, 0x5c, 0x00, 0xb0, 0xf3, 0x71, 0x1c, 0xe7, 0x07, 0x08, 0x0b, 0x0c,
        0x21, 0x20, 0xf7, 0xeb, 0x03, 0x00, 0x00, 0xc2, 0xdf, 0xfe, 0xff, 0x03, 0x01, 0xea, 0x16,
        0x0c, 0x95, 0xf4, 0xff, 0xbb, 0x8e, 0x20, 0x1f, 0x5a, 0xf7, 0x01, 0x00, 0xa0, 0x44, 0x01,
        0x00, 0x8f, 0x03, 0x00, 0x00, 0x93, 0x05, 0x00, 0x00, 0xf8, 0xff, 0xff, 0xff, 0xfb, 0xff,
        0xff, 0xff, 0x13, 0x00, 0x00, 0x00, 0x09, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xac,
        0x00, 0x00, 0x00, 0xd6, 0x7d, 0xd9, 0x00, 0x76, 0x00, 0x00, 0x00, 0xee, 0x13, 0x4f, 0x2f,
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xbc, 0x7f,
    ];

    let mut ins = Ins::new(Config::default(), AidingConfig::default());
    let mut gps = GpsAiding::new(GpsAidingConfig::default());
    let mut parser = Parser::new();
    let mut last = None;
    // Warm up: a few seconds of predicts with history and fixes, so nothing is gated.
    for k in 0..1000u32 {
        let _ = ins.predict(black_box([0.0; 3]), black_box([0.0, 0.0, -9.805]), 0.002);
        let t = u64::from(k) * 2000;
        gps.record(t, &ins.state());
        if k % 50 == 49 {
            parser.feed(&FRAME, |f| last = Some(Message::from_frame(&f)));
            if let Some(Message::NavPvt(p)) = last {
                let _ = gps.fuse(&mut ins, &p, t);
            }
        }
    }
    let mut frame = None;
    m4count_marker();
    parser.feed(black_box(&FRAME), |f| {
        frame = Some((f.class, f.id, f.payload.len()));
        last = Some(Message::from_frame(black_box(&f)));
    });
    m4count_marker();
    let msg = black_box(last);
    if let Some(Message::NavPvt(p)) = msg {
        let _ = black_box(gps.fuse(&mut ins, black_box(&p), black_box(2_000_000)));
    }
    m4count_marker();
    black_box((&ins, frame));
    exit()
}

#[cfg(not(target_os = "none"))]
fn main() {}
