//! The images of `cargo xtask dist`, unchanged, from reset through `embassy_stm32::init`
//! into the executor until every task has been polled, on a board that answers nothing
//! (the world's boards bring the chips). They need the images: run after `cargo xtask dist`
//! with `cargo test -p pil --release -- --ignored boots_` (`PIL_DIST` names another
//! folder).

use std::path::PathBuf;

use super::Config;
use super::mcu::Mcu;
use super::testing::Board;
use crate::wire::Pin;
use crate::world::machine::Machine;

fn dist(name: &str) -> Vec<u8> {
    let dir = std::env::var("PIL_DIST").map_or_else(
        |_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../dist"),
        PathBuf::from,
    );
    let path = dir.join(name);
    std::fs::read(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (build the images first: cargo xtask dist)",
            path.display()
        )
    })
}

/// Boots `name` for at most a second of virtual time; every task must be polled and
/// nothing the image touches may be unmodelled.
fn boots(name: &str, tasks: usize) {
    let mut mcu = Mcu::new(Board::default(), Config::default(), &dist(name)).unwrap();
    let mut t = 0;
    while mcu.boot_ns().is_none() && t < 1_000_000_000 {
        t += 10_000_000;
        mcu.run_until(t).unwrap();
    }
    let stats = mcu.stats();
    println!(
        "{name}: every task polled at {:.1} ms, {} instructions, stack {} bytes, entry 0x{:08x}",
        stats.boot_ns.unwrap_or(0) as f64 / 1e6,
        stats.instructions,
        stats.max_stack_bytes().unwrap_or(0),
        mcu.entry().vector_table
    );
    assert_eq!(mcu.tasks_polled(), (tasks, tasks));
    assert!(
        mcu.tasks().all(|p| p.name.is_some()),
        "task names from the v0 mangling"
    );
    let boot = stats.boot_ns.expect("every task polled within a second");
    assert!((50_000_000..200_000_000).contains(&boot), "{boot} ns");
    assert!(
        mcu.soc().unmodelled().is_empty(),
        "{:#?}",
        mcu.soc().unmodelled()
    );
    let violations: Vec<&str> = mcu
        .soc()
        .violations()
        .iter()
        .map(|v| v.what.as_str())
        .collect();
    assert_eq!(violations.len(), 1, "{violations:#?}");
    assert!(
        violations[0].starts_with("RCC +0x8c written"),
        "{violations:#?}"
    );
    assert_eq!(mcu.soc().clocks().hclk, 168_000_000);
    assert_eq!(stats.resets, 0);
}

#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn boots_brushedsparky() {
    boots("flight-brushedsparky.elf", 13);
}

#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn boots_sparky2() {
    boots("flight-sparky2.elf", 13);
}

#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn boots_brushedsparky_behind_the_taulabs_bootloader() {
    boots("flight-brushedsparky-taulabs-bl.elf", 13);
}

#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn boots_sparky2_behind_the_taulabs_bootloader() {
    boots("flight-sparky2-taulabs-bl.elf", 13);
}

/// Runs `mcu` to `until_ns` in 10 ms steps.
fn run(mcu: &mut Mcu<Board>, until_ns: u64) {
    let mut t = mcu.now_ns();
    while t < until_ns {
        t = (t + 10_000_000).min(until_ns);
        mcu.run_until(t).unwrap();
    }
}

/// Issue 29, "stuck I²C → boot loop": a slave holding SDA low for good (the bus clear
/// cannot free it here: the board's SDA is tied low). The baro task's transactions time out,
/// the baro is declared failed and excused from the watchdog: no reset, every task runs.
/// (The glue before the fix boot-looped: `tests/findings.rs`, `i2c-unguarded`.)
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn a_bus_held_low_for_good_never_resets_the_board() {
    let mut board = Board::default();
    board.levels.insert(Pin::new(1, 8), true);
    board.levels.insert(Pin::new(1, 9), false);
    let mut mcu = Mcu::new(board, Config::default(), &dist("flight-brushedsparky.elf")).unwrap();
    run(&mut mcu, 2_000_000_000);
    let stats = mcu.stats();
    assert_eq!(stats.watchdog_resets, 0, "{stats:?}");
    assert_eq!(stats.resets, 0);
    assert_eq!(mcu.tasks_polled(), (13, 13));
}

/// Issue 29, "boot hangs on missing clocks": with the HSE dead, the image's bounded probe
/// gives up after 20 ms and builds the same 168 MHz tree from the HSI; every task runs.
/// (Before the fix embassy's set-up polled HSERDY forever at 16 MHz, before the watchdog
/// existed.)
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn a_dead_hse_falls_back_to_the_hsi() {
    let mut mcu = Mcu::new(
        Board::default(),
        Config::default(),
        &dist("flight-brushedsparky.elf"),
    )
    .unwrap();
    mcu.soc_mut().set_hse_fault(true);
    run(&mut mcu, 1_000_000_000);
    assert_eq!(mcu.tasks_polled(), (13, 13));
    assert_eq!(mcu.stats().resets, 0);
    assert_eq!(mcu.soc().clocks().hclk, 168_000_000);
    let boot_ms = mcu.boot_ns().unwrap_or(u64::MAX) as f64 / 1e6;
    println!("dead HSE: every task polled at {boot_ms:.1} ms");
    // The usual ≈ 125 ms plus the probe's 20 ms limit, with a margin.
    assert!(boot_ms < 155.0, "{boot_ms} ms");
}

/// Issue 29, "boot hangs on missing clocks", the RNG: embassy's `Rng::new` waits for DRDY
/// forever; the image reads the RNG by register under a 1 ms limit and seeds from the unique
/// ID and the cycle counter otherwise — every task runs, the boot no more than the limit
/// longer.
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn a_dead_rng_never_holds_the_boot() {
    let boot_ms = |dead: bool| {
        let mut mcu = Mcu::new(
            Board::default(),
            Config::default(),
            &dist("flight-brushedsparky.elf"),
        )
        .unwrap();
        mcu.soc_mut().set_rng_fault(dead);
        run(&mut mcu, 1_000_000_000);
        assert_eq!(mcu.tasks_polled(), (13, 13), "dead RNG {dead}");
        assert_eq!(mcu.stats().resets, 0);
        mcu.boot_ns().unwrap_or(u64::MAX) as f64 / 1e6
    };
    let (alive, dead) = (boot_ms(false), boot_ms(true));
    println!("every task polled at {alive:.1} ms, {dead:.1} ms with a dead RNG");
    assert!(dead < alive + 2.0, "{dead} ms against {alive} ms");
}

/// Issue 29, "flash accelerator off": after the boot FLASH_ACR holds 5 wait states with
/// both caches on (and the prefetch, on silicon past revision A). (Built `flash-slow`, the
/// glue before the fix, the CPU load rises by a third: `tests/findings.rs`.)
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn the_flash_accelerator_is_on_after_the_boot() {
    let mut mcu = Mcu::new(
        Board::default(),
        Config::default(),
        &dist("flight-brushedsparky.elf"),
    )
    .unwrap();
    run(&mut mcu, 300_000_000);
    let t = mcu.now_ns();
    let acr = m4_sim::Bus::read(mcu.soc_mut(), 0x4002_3C00, m4_sim::Width::Word, t).unwrap();
    println!("FLASH_ACR = {acr:#06x}");
    assert_eq!(acr & 0x60F, 0x605, "latency 5, I-cache and D-cache on");
}

/// Issue 29, "DAC tones start with a click": the DAC is brought to the tone's centre (0.5 V,
/// 620 counts) when the tone task starts, with the boot, and stays there between tones — no
/// step from 0 V when the first tone starts or ends. (What remains is the enable's 0 V
/// during the boot: one step before any tone, at power-up.)
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn the_dac_rests_at_the_tone_centre_from_the_boot() {
    let mut mcu = Mcu::new(
        Board::default(),
        Config::default(),
        &dist("flight-brushedsparky.elf"),
    )
    .unwrap();
    run(&mut mcu, 2_000_000_000);
    let history = mcu.soc_mut().take_dac_history();
    println!("DAC: {history:?}");
    let centre = history
        .iter()
        .position(|s| s.volts.is_some_and(|v| (v - 0.4995).abs() < 1e-3))
        .expect("the DAC at its centre");
    let at = history.get(centre).map_or(u64::MAX, |s| s.at_ns);
    assert!(at < 200_000_000, "at the centre with the boot: {at} ns");
    assert!(
        history
            .iter()
            .skip(centre)
            .all(|s| s.volts.is_none_or(|v| v > 0.1)),
        "never back at 0 V: {history:?}"
    );
}

/// The console over USB: a host plugged in enumerates the CDC ACM device the image builds
/// and gets the answer to a typed line.
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn the_usb_console_answers_a_typed_line() {
    let mut mcu = Mcu::new(
        Board::default(),
        Config::default(),
        &dist("flight-brushedsparky.elf"),
    )
    .unwrap();
    run(&mut mcu, 200_000_000);
    mcu.soc_mut().usb_plug(true);
    run(&mut mcu, 500_000_000);
    assert_eq!(
        mcu.soc().usb_host().state(),
        &super::usb_host::HostState::Ready,
        "{:?}",
        mcu.soc().usb_host().log()
    );
    mcu.soc_mut().usb_send(b"help\n");
    run(&mut mcu, 600_000_000);
    let answer = String::from_utf8(mcu.soc_mut().usb_take_received()).unwrap();
    println!("console: {answer:?}");
    assert!(answer.starts_with("help | list"), "{answer:?}");
    assert!(answer.ends_with("\r\n"));
}

/// Settings changes and saves over the console, one every 400 ms from a blank settings
/// area, 20 of them — past the save that fills the first 16 KiB page and migrates it — never
/// reset the chip, and the last value reads back. A watchdog reset is reported with the task
/// the executor was in (task names from the v0 mangling). Fails with main's images of
/// 5 Dec: the watchdog resets the chip about 155 ms into a poll of `gains_task` after a
/// `set` (the 15th, at 6.2 s); with the images before h-harden's supervisor, a save outlasted
/// the 500 ms the unchecked stretch gave. Not in CI until fixed.
#[test]
#[ignore = "a finding of issue 29, fails until fixed; needs the images: cargo xtask dist"]
fn settings_saves_over_the_console_never_reset_the_chip() {
    let mut mcu = Mcu::new(
        Board::default(),
        Config::default(),
        &dist("flight-brushedsparky.elf"),
    )
    .unwrap();
    run(&mut mcu, 200_000_000);
    mcu.soc_mut().usb_plug(true);
    let ready =
        |mcu: &Mcu<Board>| mcu.soc().usb_host().state() == &super::usb_host::HostState::Ready;
    let mut t = 200_000_000;
    let mut saved = 0;
    while saved < 20 {
        t += 100_000_000;
        run(&mut mcu, t);
        if !ready(&mcu) {
            continue;
        }
        mcu.soc_mut()
            .usb_send(format!("set arm.min_us {}\nsave\n", 1700 + saved).as_bytes());
        t += 300_000_000;
        run(&mut mcu, t);
        let answer = String::from_utf8(mcu.soc_mut().usb_take_received()).unwrap();
        if let Some(bite) = mcu.watchdog_bites().first() {
            panic!(
                "save {saved}: watchdog reset at {:.1} ms, {:.1} ms into a poll of {} ({answer:?})",
                bite.at_ns as f64 / 1e6,
                (bite.at_ns - bite.polled_at_ns) as f64 / 1e6,
                bite.last_polled
                    .as_ref()
                    .map_or("?".into(), ToString::to_string)
            );
        }
        assert!(answer.ends_with("saving\r\n"), "{answer:?}");
        saved += 1;
    }
    t += 3_000_000_000;
    run(&mut mcu, t);
    let _ = mcu.soc_mut().usb_take_received();
    mcu.soc_mut().usb_send(b"get arm.min_us\n");
    t += 100_000_000;
    run(&mut mcu, t);
    let answer = String::from_utf8(mcu.soc_mut().usb_take_received()).unwrap();
    println!("erases {:?}", mcu.soc().flash_erases());
    assert_eq!(
        answer.trim_end(),
        format!("arm.min_us = {}", 1700 + saved - 1)
    );
    assert!(mcu.watchdog_bites().is_empty());
}

/// Embassy's time on the emulated chip keeps virtual time: the heartbeat LED (PB5, active
/// low, a 50 ms `Ticker` × 20) turns on once a second. A `Ticker` schedules from its own
/// deadlines, so late wake-ups do not add up — only a TIM2 count that runs slow or fast
/// does. Measured over 10 s: within ±20 ppm.
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn the_heartbeat_keeps_virtual_time() {
    let mut mcu = Mcu::new(
        Board::default(),
        Config::default(),
        &dist("flight-brushedsparky.elf"),
    )
    .unwrap();
    run(&mut mcu, 11_500_000_000);
    let on: Vec<u64> = mcu
        .soc()
        .outside()
        .edges(Pin::new(1, 5))
        .into_iter()
        .filter(|&(d, t)| d == crate::wire::Drive::Low && t > 1_000_000_000)
        .map(|(_, t)| t)
        .collect();
    assert!(on.len() >= 11, "{on:?}");
    let (first, last) = (on[0], on[10]);
    let period_ns = (last - first) as f64 / 10.0;
    let ppm = (period_ns / 1e9 - 1.0) * 1e6;
    println!("heartbeat: {period_ns:.0} ns over 10 periods, {ppm:+.1} ppm");
    assert!(ppm.abs() <= 20.0, "{ppm:+.1} ppm");
}
