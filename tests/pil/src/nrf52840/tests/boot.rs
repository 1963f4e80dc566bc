//! The real images of `cargo xtask dist` from reset through `embassy_nrf::init` into the
//! executor, until every task the default settings spawn has been polled: the probe image
//! on an erased chip, the UF2 image behind the MBR and bootloader stand-ins. Run after
//! `cargo xtask dist`: `cargo test -p pil --release nrf52840::tests::boot -- --ignored
//! --nocapture` (`PIL_DIST=dir` points at another dist folder).

use std::collections::BTreeMap;
use std::path::PathBuf;

use m4_sim::bus::ResetCause;
use m4_sim::{Config as CpuConfig, Cpu, Reg, Stop};

use crate::nrf52840::{ClockFaults, Config, Nrf52840, resetreas, uicr};
use crate::wire::{Drive, I2cReply, I2cStep, Outside, Pin};

/// A quiet board: the radio answers 0x00 to everything, nIRQ and the bind button idle high,
/// the PPM line idles high, the battery divider shows 1.3 V.
#[derive(Default)]
struct Quiet {
    spi_bytes: u64,
}

impl Outside for Quiet {
    fn pin_driven(&mut self, _pin: Pin, _drive: Drive, _now_ns: u64) {}
    fn pin_level(&mut self, pin: Pin, _now_ns: u64) -> Option<bool> {
        match (pin.port, pin.pin) {
            (0, 11) | (1, 15) | (1, 4) => Some(true),
            _ => None,
        }
    }
    fn spi_byte(&mut self, _bus: u8, _mosi: u8, _now_ns: u64) -> u8 {
        self.spi_bytes += 1;
        0
    }
    fn i2c_step(&mut self, _bus: u8, _step: I2cStep, _now_ns: u64) -> I2cReply {
        I2cReply::Nack
    }
    fn uart_sent(&mut self, _uart: u8, _byte: u8, _now_ns: u64) {}
    fn analog_volts(&mut self, _pin: Pin, _now_ns: u64) -> f32 {
        1.3
    }
}

fn dist(name: &str) -> Vec<u8> {
    let dir = std::env::var_os("PIL_DIST").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../dist"),
        PathBuf::from,
    );
    let path = dir.join(name);
    std::fs::read(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (run cargo xtask dist)", path.display()))
}

/// The nRF52840's core: 3 priority bits, 48 interrupts, no SysTick reference clock.
fn core() -> Cpu {
    Cpu::new(CpuConfig {
        prio_bits: 3,
        irqs: 48,
        systick_ref_div: None,
        systick_tenms: 0,
        bitband: false,
        halt_on_bkpt: false,
        initial_hz: 64_000_000,
    })
}

/// What a boot showed.
struct Boot {
    chip: Nrf52840<Quiet>,
    /// Task name → time of its first poll, ns.
    polled: BTreeMap<String, u64>,
    /// Time the last expected task was first polled, ns.
    all_polled_ns: Option<u64>,
    instructions: u64,
    lowest_sp: u32,
}

/// The task a POOL symbol holds: the last identifier of its path before `POOL`, in the
/// legacy (`_ZN…`) or v0 (`_R…`, an `_` after the length of an identifier that starts with
/// one) mangling (`…5tasks6button11button_task4POOL…` → "button_task").
fn task_name(symbol: &str) -> Option<String> {
    let v0 = symbol.starts_with("_R");
    let mut rest = symbol.get(symbol.find("9module_fw")?..)?;
    let mut last = None;
    loop {
        let digits = rest.find(|c: char| !c.is_ascii_digit())?;
        let len: usize = rest.get(..digits)?.parse().ok()?;
        let mut start = digits;
        if v0 && rest.get(start..=start) == Some("_") {
            start += 1;
        }
        let name = rest.get(start..start + len)?;
        if name == "POOL" {
            return last;
        }
        last = Some(name.to_owned());
        rest = rest.get(start + len..)?;
    }
}

/// A task's poll function, in either mangling.
fn is_task_poll(symbol: &str) -> bool {
    symbol.contains("TaskStorage") && (symbol.contains("4poll17h") || symbol.contains("4pollB"))
}

fn boot(elf: &[u8], uf2: bool, expected: &[&str]) -> Boot {
    boot_with(elf, uf2, expected, Config::default())
}

fn boot_with(elf: &[u8], uf2: bool, expected: &[&str], config: Config) -> Boot {
    let mut chip = Nrf52840::new(Quiet::default(), config);
    chip.load_elf(elf).unwrap();
    if uf2 {
        chip.install_uf2_boot_chain(0x26000);
    }
    let symbols = fw_elf::symbols(elf).unwrap();
    let pools: Vec<(String, u32, u32)> = symbols
        .iter()
        .filter(|s| s.name.contains("4POOL") && s.size > 0)
        .filter_map(|s| Some((task_name(&s.name)?, s.address, s.size.max(1))))
        .collect();
    let mut cpu = core();
    for s in symbols.iter().filter(|s| is_task_poll(&s.name)) {
        cpu.add_pc_hook(s.address & !1);
    }
    let hard_fault = symbols
        .iter()
        .find(|s| s.name == "HardFault_")
        .map(|s| s.address & !1);
    if let Some(at) = hard_fault {
        cpu.add_pc_hook(at);
    }
    cpu.reset(&mut chip);
    let mut polled = BTreeMap::new();
    let mut all_polled_ns = None;
    let deadline = 5_000_000_000;
    while all_polled_ns.is_none() {
        match cpu.run_until(&mut chip, deadline) {
            Stop::Hook { pc } if Some(pc) == hard_fault => {
                let sp = cpu.read_reg(Reg::Msp);
                let word = |a: u32| {
                    let o = a.wrapping_sub(0x2000_0000) as usize;
                    chip.ram()
                        .get(o..o + 4)
                        .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                };
                panic!(
                    "HardFault at {} ns: stacked PC {:08X} LR {:08X} xPSR {:08X}; polled {polled:?}",
                    cpu.now_ns(),
                    word(sp + 24),
                    word(sp + 20),
                    word(sp + 28)
                );
            }
            Stop::Hook { .. } => {
                let header = cpu.read_reg(Reg::R(0));
                let name = pools
                    .iter()
                    .find(|(_, at, size)| (*at..at + size).contains(&header))
                    .map_or_else(|| format!("task at {header:08X}"), |p| p.0.clone());
                polled.entry(name).or_insert(cpu.now_ns());
                if expected.iter().all(|t| polled.contains_key(*t)) {
                    all_polled_ns = Some(cpu.now_ns());
                }
            }
            Stop::Deadline => break,
            other => panic!("{other:?} at {} ns; polled so far {polled:?}", cpu.now_ns()),
        }
    }
    let stats = cpu.stats();
    Boot {
        chip,
        polled,
        all_polled_ns,
        instructions: stats.instructions,
        lowest_sp: stats.lowest_sp,
    }
}

/// The tasks the default settings spawn (transmitter role, PPM input): all but the
/// receiver's PPM output.
const TASKS: [&str; 11] = [
    "__embassy_main",
    "supervisor_task",
    "status_led_task",
    "link_task",
    "app_task",
    "button_task",
    "battery_task",
    "settings_task",
    "hm10_task",
    "jr_line_task",
    "ppm_in_task",
];

fn report(name: &str, b: &Boot) {
    let at = b.all_polled_ns.map_or_else(
        || "never".to_owned(),
        |t| format!("at {:.3} ms", t as f64 / 1e6),
    );
    println!(
        "{name}: every task polled {at}, {} instructions, lowest SP 0x{:08X}, resets {:?}",
        b.instructions,
        b.lowest_sp,
        b.chip.resets()
    );
    for (task, at) in &b.polled {
        println!("  {task:<16} first polled at {:>9.3} ms", *at as f64 / 1e6);
    }
}

fn assert_clean(b: &Boot) {
    assert!(b.all_polled_ns.is_some(), "tasks polled: {:?}", b.polled);
    assert!(b.chip.unmodelled().is_empty(), "{:#?}", b.chip.unmodelled());
    assert!(b.chip.records().dma_faults().is_empty());
    assert!(
        b.chip.records().notes().is_empty(),
        "{:#?}",
        b.chip.records().notes()
    );
}

#[test]
#[ignore = "needs the images of cargo xtask dist"]
fn the_probe_image_boots_on_an_erased_chip() {
    let b = boot(&dist("module-nrf52840.elf"), false, &TASKS);
    report("module-nrf52840.elf", &b);
    assert_clean(&b);
    // embassy-nrf's init programs PSELRESET, NFCPINS and (build code F) APPROTECT into the
    // erased UICR and, the chip on VDDH, REGOUT0 = 3.3 V (issue 29: erased it is 1.8 V, at
    // which the radio and the HM-10 do not work), and resets once.
    let resets = b.chip.resets();
    assert_eq!(resets.len(), 1);
    assert_eq!(resets[0].cause, ResetCause::Other);
    assert_eq!(b.chip.reset_reason(), resetreas::SREQ);
    assert_eq!(b.chip.uicr_word(uicr::PSELRESET0), 18);
    assert_eq!(b.chip.uicr_word(uicr::NFCPINS) & 1, 0);
    assert_eq!(b.chip.uicr_word(uicr::APPROTECT), 0x5A);
    assert_eq!(b.chip.uicr_word(uicr::REGOUT0) & 0b111, 0b101, "VOUT 3.3 V");
    assert_eq!(b.chip.gpio_supply_volts(), 3.3);
    // The LFXO's 0.25 s start-up comes first.
    assert!(b.all_polled_ns.unwrap_or(0) > 250_000_000);
}

#[test]
#[ignore = "needs the images of cargo xtask dist"]
fn the_uf2_image_boots_behind_the_mbr_and_bootloader() {
    let b = boot(&dist("module-nrf52840-uf2.elf"), true, &TASKS);
    report("module-nrf52840-uf2.elf", &b);
    assert_clean(&b);
    assert_eq!(b.chip.gpio_supply_volts(), 3.3);
    // Interrupts arrive through the image's own table (VTOR) although the MBR forwards too.
    assert!(b.polled.contains_key("link_task"));
}

#[test]
#[ignore = "needs the images of cargo xtask dist"]
fn a_dead_32khz_crystal_falls_back_and_the_boot_goes_on() {
    let config = Config {
        clock_faults: ClockFaults {
            hfxo_dead: false,
            lfxo_dead: true,
        },
        ..Config::default()
    };
    let b = boot_with(&dist("module-nrf52840.elf"), false, &TASKS, config);
    report("module-nrf52840.elf, LFXO dead", &b);
    assert_clean(&b);
    // Issue 29, "boot hangs on missing clocks": embassy_nrf::init waits for LFCLKSTARTED
    // with no limit and no watchdog running yet; the image probes the crystal for 1 s (on
    // the cycle counter) and runs from the LFCLK synthesised from the HFXO: both boots (the
    // REGOUT0 reset between them) take the probe's second, and no more.
    let at = b.all_polled_ns.unwrap_or(u64::MAX);
    assert!(
        (2_000_000_000..2_600_000_000).contains(&at),
        "every task polled at {at} ns"
    );
    assert_eq!(b.chip.watchdog_timeouts(), 0);
    assert_eq!(b.chip.resets().len(), 1, "only init's UICR reset");
}

#[test]
#[ignore = "needs the images of cargo xtask dist"]
fn a_dead_32mhz_crystal_falls_back_to_the_hfint() {
    let config = Config {
        clock_faults: ClockFaults {
            hfxo_dead: true,
            lfxo_dead: false,
        },
        ..Config::default()
    };
    let b = boot_with(&dist("module-nrf52840.elf"), false, &TASKS, config);
    report("module-nrf52840.elf, HFXO dead", &b);
    assert_clean(&b);
    assert!(!b.chip.hfxo_running());
    assert_eq!(b.chip.watchdog_timeouts(), 0);
}

#[test]
#[ignore = "needs the images of cargo xtask dist"]
fn three_seconds_on_a_silent_board() {
    let mut chip = Nrf52840::new(Quiet::default(), Config::default());
    chip.load_elf(&dist("module-nrf52840.elf")).unwrap();
    let mut cpu = core();
    cpu.reset(&mut chip);
    let stop = cpu.run_until(&mut chip, 3_000_000_000);
    assert_eq!(stop, Stop::Deadline);
    let s = cpu.stats();
    let a = chip.anomaly_198();
    println!(
        "3 s: {} instructions, {} cycles active, {} asleep; watchdog expiries {}; anomaly 198: \
         {} conditions in {} SPIM3 transfers, first {:?}",
        s.instructions,
        s.cycles_active,
        s.cycles_asleep,
        chip.watchdog_timeouts(),
        a.count,
        a.transfers,
        a.hits.first()
    );
    assert!(chip.unmodelled().is_empty(), "{:#?}", chip.unmodelled());
    assert!(
        chip.records().notes().is_empty(),
        "{:#?}",
        chip.records().notes()
    );
    assert_eq!(chip.watchdog_timeouts(), 0);
    assert!(s.cycles_asleep > s.cycles_active);
}

#[test]
fn task_names_come_out_of_both_manglings() {
    assert_eq!(
        task_name("_ZN9module_fw8firmware5tasks6button11button_task4POOL17hd17b4ca2ea4460c2E"),
        Some("button_task".into())
    );
    assert_eq!(
        task_name("_RNvNvNtNtNtCs8WT4Z81vMpu_9module_fw8firmware5tasks4hm109hm10_task4POOL"),
        Some("hm10_task".into())
    );
    assert_eq!(
        task_name("_RNvNvNtCs8WT4Z81vMpu_9module_fw8firmware14___embassy_main4POOL"),
        Some("__embassy_main".into())
    );
    assert!(is_task_poll(
        "_RNvMs1_NtCsjd7thcCjObs_16embassy_executor3rawINtB5_11TaskStorageNCNvNvNtNtNtCs8WT4Z81vMpu_9module_fw8firmware5tasks4link16___link_task_task31___link_task_task_inner_function0E4pollB1c_"
    ));
}
