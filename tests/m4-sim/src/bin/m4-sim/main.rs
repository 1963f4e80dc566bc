//! `m4-sim`: runs bare-metal Cortex-M4F programs on the emulator with the flat
//! `mps2-an386` memory map and counts instructions between marker calls as m4count does
//! under QEMU (`run`), checks both agree (`compare`), checks every instruction of firmware
//! images decodes (`coverage`), and measures emulation speed (`speed`).

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::Instant;

use clap::{Parser, Subcommand};
use m4_sim::{Config, Cpu, FlatBus, Stop};

mod difftest;

#[derive(Parser)]
#[command(
    name = "m4-sim",
    about = "Cortex-M4F emulator: run, compare with QEMU, decode coverage, speed"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Run a program to its semihosting exit; print the instructions between calls of the
    /// marker function as m4count prints them.
    Run {
        /// The ELF file (thumbv7em, linked for mps2-an386).
        elf: PathBuf,
        /// The marker symbol.
        #[arg(long, default_value = "m4count_marker")]
        marker: String,
        /// Also print cycles per region and the run's statistics.
        #[arg(long)]
        cycles: bool,
        /// Give up after this many seconds of virtual time.
        #[arg(long, default_value_t = 600)]
        timeout: u64,
    },
    /// Run each program under m4count (QEMU) and under m4-sim; fail on any difference in a
    /// region count or the total.
    Compare {
        /// The ELF files.
        #[arg(required = true)]
        elfs: Vec<PathBuf>,
        /// The m4count script (default: $M4COUNT, or ../shared/tools/m4count/m4count).
        #[arg(long)]
        m4count: Option<PathBuf>,
    },
    /// Check that every instruction in the code of each ELF (its `$t` ranges) decodes to
    /// something other than UNDEFINED.
    Coverage {
        /// The ELF files (e.g. dist/*.elf).
        #[arg(required = true)]
        elfs: Vec<PathBuf>,
    },
    /// Run programs to their exit and print instructions per second of host time.
    Speed {
        /// The ELF files.
        #[arg(required = true)]
        elfs: Vec<PathBuf>,
    },
    /// Differential test against QEMU: random ALU/DSP/FPU programs run under both; any
    /// difference in the final registers is reported with the instruction that causes it.
    /// Needs llvm-mc, rust-lld (the Rust toolchain's) and qemu-system-arm.
    Diff {
        /// Seed of the program generator.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// How many programs.
        #[arg(long, default_value_t = 50)]
        programs: u32,
        /// Instructions (or IT blocks, or FPSCR changes) per program.
        #[arg(long, default_value_t = 60)]
        length: usize,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.cmd {
        Cmd::Run {
            elf,
            marker,
            cycles,
            timeout,
        } => run_cmd(&elf, &marker, cycles, timeout),
        Cmd::Compare { elfs, m4count } => compare(&elfs, m4count),
        Cmd::Coverage { elfs } => coverage(&elfs),
        Cmd::Speed { elfs } => speed(&elfs),
        Cmd::Diff {
            seed,
            programs,
            length,
        } => diff(seed, programs, length),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("m4-sim: {e}");
            ExitCode::FAILURE
        }
    }
}

/// What one run of a program produced.
pub(crate) struct Outcome {
    /// Instruction count at each marker call.
    marks: Vec<u64>,
    /// Cycle count at each marker call.
    mark_cycles: Vec<u64>,
    total: u64,
    exit_code: u32,
    pub(crate) output: Vec<u8>,
    cpu: Cpu,
}

fn read(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// Loads an ELF's segments into a fresh mps2-an386 bus.
fn load(elf: &[u8], path: &Path) -> Result<FlatBus, String> {
    let segments = fw_elf::load_segments(elf).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut bus = FlatBus::mps2_an386();
    for s in &segments {
        if !bus.load(s.address, &s.data) {
            return Err(format!(
                "{}: segment at 0x{:08x} ({} bytes) is outside mps2-an386's flash and RAM",
                path.display(),
                s.address,
                s.data.len()
            ));
        }
    }
    Ok(bus)
}

/// The address of a function symbol: exact name, or a Rust path ending in it.
fn symbol(elf: &[u8], name: &str) -> Result<Option<u32>, String> {
    let symbols = fw_elf::symbols(elf).map_err(|e| e.to_string())?;
    Ok(symbols
        .iter()
        .find(|s| s.name == name || s.name.ends_with(&format!("::{name}")))
        .map(|s| s.address & !1))
}

/// Runs a program to its exit, recording the instruction count at each marker call.
pub(crate) fn execute(path: &Path, marker: &str, timeout_s: u64) -> Result<Outcome, String> {
    let elf = read(path)?;
    let mut bus = load(&elf, path)?;
    let marker_addr = symbol(&elf, marker)?;
    let mut cpu = Cpu::new(Config {
        halt_on_bkpt: true,
        ..Config::default()
    });
    cpu.reset(&mut bus);
    if let Some(a) = marker_addr {
        cpu.add_pc_hook(a);
    }
    let (mut marks, mut mark_cycles) = (Vec::new(), Vec::new());
    let deadline = timeout_s.saturating_mul(1_000_000_000);
    let exit_code = loop {
        match cpu.run_until(&mut bus, deadline) {
            Stop::Hook { .. } => {
                marks.push(cpu.stats().instructions);
                mark_cycles.push(cpu.cycles());
            }
            Stop::Exit { code } => break code,
            Stop::Deadline => {
                return Err(format!(
                    "{}: no exit after {timeout_s} s of virtual time (pc 0x{:08x})",
                    path.display(),
                    cpu.read_reg(m4_sim::Reg::R(15))
                ));
            }
            Stop::Breakpoint { pc, imm } => {
                return Err(format!("{}: BKPT #{imm} at 0x{pc:08x}", path.display()));
            }
            Stop::Lockup { pc } => {
                return Err(format!(
                    "{}: the core locked up at 0x{pc:08x} ({})",
                    path.display(),
                    fault_summary(&mut cpu, &mut bus)
                ));
            }
        }
    };
    let output = cpu.take_semihost_output();
    Ok(Outcome {
        marks,
        mark_cycles,
        total: cpu.stats().instructions,
        exit_code,
        output,
        cpu,
    })
}

/// The fault status registers, for a lockup report.
fn fault_summary(cpu: &mut Cpu, bus: &mut FlatBus) -> String {
    let _ = bus;
    format!(
        "xPSR 0x{:08x}, LR 0x{:08x}",
        cpu.read_reg(m4_sim::Reg::Xpsr),
        cpu.read_reg(m4_sim::Reg::R(14))
    )
}

/// Region counts between consecutive marks (as m4count: the difference of the counts).
fn regions(marks: &[u64]) -> Vec<u64> {
    marks
        .iter()
        .zip(marks.iter().skip(1))
        .map(|(a, b)| b - a)
        .collect()
}

fn run_cmd(path: &Path, marker: &str, cycles: bool, timeout: u64) -> Result<(), String> {
    let out = execute(path, marker, timeout)?;
    print!("{}", String::from_utf8_lossy(&out.output));
    let cyc = regions(&out.mark_cycles);
    for (i, n) in regions(&out.marks).iter().enumerate() {
        if cycles {
            let c = cyc.get(i).copied().unwrap_or(0);
            println!("region {}: {n} instructions, {c} cycles", i + 1);
        } else {
            println!("region {}: {n} instructions", i + 1);
        }
    }
    println!("total {}", out.total);
    if cycles {
        let s = out.cpu.stats();
        println!(
            "cycles {} (active {}, asleep {}), lowest SP 0x{:08x}",
            out.cpu.cycles(),
            s.cycles_active,
            s.cycles_asleep,
            s.lowest_sp
        );
    }
    if out.exit_code != 0 {
        return Err(format!("{}: exit status {}", path.display(), out.exit_code));
    }
    Ok(())
}

/// m4count's `region N: X instructions` lines and its `total X`.
fn parse_m4count(text: &str) -> (Vec<u64>, Option<u64>) {
    let mut regions = Vec::new();
    let mut total = None;
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["region", _, n, "instructions"] => {
                if let Ok(n) = n.parse() {
                    regions.push(n);
                }
            }
            ["total", n] => total = n.parse().ok(),
            _ => {}
        }
    }
    (regions, total)
}

fn m4count_path(given: Option<PathBuf>) -> PathBuf {
    given
        .or_else(|| std::env::var_os("M4COUNT").map(PathBuf::from))
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/tools/m4count/m4count")
        })
}

fn compare(elfs: &[PathBuf], m4count: Option<PathBuf>) -> Result<(), String> {
    let m4count = m4count_path(m4count);
    let mut failed = 0;
    for path in elfs {
        let qemu = Command::new(&m4count)
            .arg(path)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", m4count.display()))?;
        if !qemu.status.success() {
            return Err(format!(
                "m4count failed on {}: {}",
                path.display(),
                String::from_utf8_lossy(&qemu.stderr).trim()
            ));
        }
        let (q_regions, q_total) = parse_m4count(&String::from_utf8_lossy(&qemu.stdout));
        let ours = execute(path, "m4count_marker", 600)?;
        let s_regions = regions(&ours.marks);
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        let same_total = q_total.is_none_or(|t| t == ours.total);
        if q_regions == s_regions && same_total {
            println!(
                "ok   {name:<16} {} regions, total {} instructions",
                s_regions.len(),
                ours.total
            );
            continue;
        }
        failed += 1;
        println!("FAIL {name:<16} QEMU and m4-sim differ");
        let n = q_regions.len().max(s_regions.len());
        for i in 0..n {
            let (q, s) = (q_regions.get(i), s_regions.get(i));
            if q != s {
                println!("       region {}: QEMU {q:?}, m4-sim {s:?}", i + 1);
            }
        }
        if !same_total {
            println!("       total: QEMU {q_total:?}, m4-sim {}", ours.total);
        }
    }
    if failed > 0 {
        return Err(format!("{failed} program(s) differ"));
    }
    Ok(())
}

fn coverage(elfs: &[PathBuf]) -> Result<(), String> {
    let mut bad_total = 0;
    for path in elfs {
        let elf = read(path)?;
        let segments =
            fw_elf::load_segments(&elf).map_err(|e| format!("{}: {e}", path.display()))?;
        let sections =
            fw_elf::alloc_sections(&elf).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut maps: Vec<(u32, bool)> = fw_elf::symbols(&elf)
            .map_err(|e| format!("{}: {e}", path.display()))?
            .iter()
            .filter_map(|s| match s.name.get(..2) {
                Some("$t") => Some((s.address, true)),
                Some("$d") | Some("$a") => Some((s.address, false)),
                _ => None,
            })
            .collect();
        maps.sort_unstable();
        maps.dedup();
        let halfword = |addr: u32| -> Option<u16> {
            segments.iter().find_map(|s| {
                let off = addr.checked_sub(s.address)? as usize;
                let b = s.data.get(off..off + 2)?;
                Some(u16::from_le_bytes([*b.first()?, *b.get(1)?]))
            })
        };
        let (mut checked, mut bad) = (0u64, 0u64);
        for (i, &(start, code)) in maps.iter().enumerate() {
            if !code {
                continue;
            }
            let section_end = sections
                .iter()
                .find(|s| start >= s.address && start < s.address.wrapping_add(s.size))
                .map_or(start, |s| s.address + s.size);
            let end = maps
                .get(i + 1)
                .map_or(section_end, |&(next, _)| next.min(section_end));
            let mut addr = start;
            while addr + 2 <= end {
                let Some(hw1) = halfword(addr) else { break };
                let hw2 = halfword(addr + 2).unwrap_or(0);
                let (ok, len) = m4_sim::decode::is_defined(hw1, hw2);
                checked += 1;
                if !ok {
                    bad += 1;
                    if bad <= 20 {
                        println!(
                            "  {}: 0x{addr:08x}: {hw1:04x} {hw2:04x} is UNDEFINED",
                            path.display()
                        );
                    }
                }
                addr += u32::from(len);
            }
        }
        println!(
            "{} {}: {checked} instructions, {bad} undefined",
            if bad == 0 { "ok  " } else { "FAIL" },
            path.display()
        );
        bad_total += bad;
    }
    if bad_total > 0 {
        return Err(format!("{bad_total} instruction(s) do not decode"));
    }
    Ok(())
}

fn diff(seed: u64, programs: u32, length: usize) -> Result<(), String> {
    let tools = difftest::Tools::find()?;
    let failures = difftest::run(&tools, seed, programs, length)?;
    if failures > 0 {
        return Err(format!(
            "{failures} of {programs} programs differ from QEMU"
        ));
    }
    println!("ok   {programs} programs of {length} instructions agree with QEMU (seed {seed})");
    Ok(())
}

/// CPU time this process has used (Linux's schedstat, in ns), or `None` elsewhere.
fn cpu_time_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// Runs each program `REPEAT` times and reports the best run: instructions per second of
/// CPU time (wall-clock time where CPU time is not available), so other load on the
/// machine does not count.
fn speed(elfs: &[PathBuf]) -> Result<(), String> {
    const REPEAT: usize = 3;
    let (mut insns, mut secs) = (0u64, 0f64);
    for path in elfs {
        let mut best = f64::INFINITY;
        let mut total = 0;
        for _ in 0..REPEAT {
            let (cpu0, wall0) = (cpu_time_ns(), Instant::now());
            let out = execute(path, "m4count_marker", 600)?;
            let t = match (cpu0, cpu_time_ns()) {
                (Some(a), Some(b)) => (b - a) as f64 / 1e9,
                _ => wall0.elapsed().as_secs_f64(),
            };
            best = best.min(t);
            total = out.total;
        }
        println!(
            "{:<24} {:>10} instructions in {:>6.3} s: {:>6.1} M instructions/s",
            path.file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
            total,
            best,
            total as f64 / best / 1e6
        );
        insns += total;
        secs += best;
    }
    println!(
        "all: {insns} instructions in {secs:.3} s of CPU time: {:.1} M instructions/s",
        insns as f64 / secs / 1e6
    );
    Ok(())
}
