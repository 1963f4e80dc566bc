//! The images of `cargo xtask dist`, unchanged, from reset through `embassy_stm32::init`
//! into the executor until every task has been polled, on a board that answers nothing
//! (the world's boards bring the chips). They need the images: run after `cargo xtask dist`
//! with `cargo test -p pil --release -- --ignored boots_` (`PIL_DIST` names another
//! folder).

use std::path::PathBuf;

use super::Config;
use super::mcu::Mcu;
use super::testing::Board;
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
