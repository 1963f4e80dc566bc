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
    boots("flight-brushedsparky.elf", 12);
}

#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn boots_sparky2() {
    boots("flight-sparky2.elf", 13);
}

#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn boots_brushedsparky_behind_the_taulabs_bootloader() {
    boots("flight-brushedsparky-taulabs-bl.elf", 12);
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

/// Issue 29, "stuck I²C → boot loop": an MS5611 holding SDA low. No START ever reaches the
/// bus, the baro task waits for SB forever, the watchdog resets the board, and the next
/// boot hangs the same way.
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn a_stuck_i2c_bus_is_a_boot_loop() {
    let mut board = Board::default();
    board.levels.insert(Pin::new(1, 8), true);
    board.levels.insert(Pin::new(1, 9), false);
    let mut mcu = Mcu::new(board, Config::default(), &dist("flight-brushedsparky.elf")).unwrap();
    run(&mut mcu, 2_000_000_000);
    let stats = mcu.stats();
    println!(
        "stuck bus: {} watchdog resets in 2 s",
        stats.watchdog_resets
    );
    assert!(stats.watchdog_resets >= 2, "{stats:?}");
    assert!(mcu.soc().outside().i2c.is_empty(), "no START on a held bus");
}

/// Issue 29, "boot hangs on missing clocks": with the HSE dead, embassy's clock set-up
/// polls HSERDY forever at 16 MHz, before the watchdog exists: no task, no reset.
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn a_dead_hse_hangs_the_boot_before_the_watchdog() {
    let mut mcu = Mcu::new(
        Board::default(),
        Config::default(),
        &dist("flight-brushedsparky.elf"),
    )
    .unwrap();
    mcu.soc_mut().set_hse_fault(true);
    run(&mut mcu, 1_000_000_000);
    assert_eq!(
        mcu.tasks_polled().1,
        1,
        "main's first poll runs embassy_stm32::init"
    );
    assert_eq!(mcu.stats().resets, 0);
    assert_eq!(mcu.soc().clocks().hclk, 16_000_000);
}

/// Issue 29, "flash accelerator off": embassy leaves FLASH_ACR at LATENCY only, so every
/// 128-bit line costs 5 wait states; the same boot with prefetch and both caches on (set
/// once the clocks run, as the fix will) polls every task sooner.
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn the_flash_accelerator_shortens_the_boot() {
    let boot_ms = |accelerated: bool| {
        let mut mcu = Mcu::new(
            Board::default(),
            Config::default(),
            &dist("flight-brushedsparky.elf"),
        )
        .unwrap();
        run(&mut mcu, 10_000_000);
        if accelerated {
            let t = mcu.now_ns();
            let acr =
                m4_sim::Bus::read(mcu.soc_mut(), 0x4002_3C00, m4_sim::Width::Word, t).unwrap();
            m4_sim::Bus::write(
                mcu.soc_mut(),
                0x4002_3C00,
                m4_sim::Width::Word,
                acr | 0x700,
                t,
            )
            .unwrap();
        }
        while mcu.boot_ns().is_none() && mcu.now_ns() < 1_000_000_000 {
            let t = mcu.now_ns() + 1_000_000;
            mcu.run_until(t).unwrap();
        }
        let art = mcu.soc().art_stats();
        let ms = mcu.boot_ns().unwrap_or(u64::MAX) as f64 / 1e6;
        println!(
            "ART {}: every task polled at {ms:.1} ms, {} stall cycles",
            if accelerated { "on" } else { "off" },
            art.stall_cycles
        );
        ms
    };
    let (off, on) = (boot_ms(false), boot_ms(true));
    assert!(on < 0.8 * off, "off {off} ms, on {on} ms");
}

/// Issue 29, "DAC tones start with a click": 0 V from the DAC's enable until the first tone
/// ends, then 0.5 V — and no tone between: the HAL never sets TEN, so TIM6's updates
/// trigger nothing and the DMA never moves a sample (with this board the first tone has
/// not ended after 2 s: the output stays at the click's 0 V).
#[test]
#[ignore = "needs the images: cargo xtask dist"]
fn the_first_tone_is_a_click_and_no_tone() {
    let mut mcu = Mcu::new(
        Board::default(),
        Config::default(),
        &dist("flight-brushedsparky.elf"),
    )
    .unwrap();
    run(&mut mcu, 2_000_000_000);
    let history = mcu.soc_mut().take_dac_history();
    let volts: Vec<f32> = history.iter().filter_map(|s| s.volts).collect();
    println!("DAC: {history:?}");
    assert_eq!(volts.first(), Some(&0.0), "0 V from the enable: the click");
    assert!(
        volts.iter().all(|&v| v == 0.0 || (v - 0.4995).abs() < 1e-3),
        "nothing but 0 V and the 0.5 V rest level: no sample of a tone"
    );
    assert!(
        volts.len() <= 2,
        "the click, then the rest level once a first tone ends"
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
