//! `cargo xtask`: builds the two firmware images (each in its own cargo invocation: their
//! embassy time drivers cannot share one build) and writes flashable files to `dist/`.
//!
//! ```text
//! cargo xtask build flight [--sparky2] [--bootloader]   # one image, release
//! cargo xtask build module [--uf2]
//! cargo xtask dist                                       # every variant → dist/*.{elf,bin,hex,uf2,tlfw}
//! cargo xtask size                                       # text/data/bss of what dist/ holds
//! cargo xtask size-report [--image NAME] [--top N]       # each image's text by crate
//! cargo xtask verify                                     # boot contracts, flash budgets, README
//! cargo xtask readme                                     # the README's size tables from dist/
//! cargo xtask figures [--check | --write]                # the docs' M4 instruction figures
//! cargo xtask web [--test]                               # the web ground station, built (and tested)
//! cargo xtask wasm                                       # its decoder and bindings only
//! ```

use fw_elf as elf;
mod budget;
mod figures;
mod formats;
mod layout;
mod size_report;
mod tlfw;
mod verify;
mod web;

use layout::Layout;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::{env, fs};

use clap::{Parser, Subcommand};

/// Builds the TauLink firmware images (release, thumbv7em-none-eabihf) and turns them into
/// flashable .bin, .hex and .uf2 files.
#[derive(Parser, Debug)]
#[command(
    name = "xtask",
    version,
    after_help = "Examples:
  cargo xtask build flight --sparky2     the Sparky2 image, prints the ELF's path
  cargo xtask build module --uf2         the nRF52840 image for a UF2 bootloader
  cargo xtask dist                       every variant -> dist/*.{elf,bin,hex,uf2}
  cargo xtask size                       text/data/bss of what dist/ holds
  cargo xtask size-report --image flight-sparky2 --top 40
                                         its text by crate and its 40 largest symbols
  cargo xtask web                        the web ground station, from a clone to its dist/
  cargo xtask web --test                 the same, then its unit and browser tests"
)]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

#[derive(Subcommand, Debug)]
enum Task {
    /// Build one firmware image (release) and print the ELF's path.
    #[command(subcommand)]
    Build(Image),
    /// Build every variant and write dist/NAME.elf, .bin and .hex (and .uf2, .tlfw where the
    /// image has them).
    Dist,
    /// Print text/data/bss of the ELFs in dist/.
    Size,
    /// Print each image's text by crate (generic code also by the crate it was instantiated
    /// for) and its largest symbols, from the ELFs in dist/.
    SizeReport {
        /// Only this image (a dist/ name, e.g. flight-sparky2); default: one of each build.
        #[arg(long, value_parser = image_name)]
        image: Option<String>,
        /// How many of the largest symbols to list.
        #[arg(long, default_value_t = 25)]
        top: usize,
        /// Read the ELFs from this folder instead of dist/ (e.g. a copy of another
        /// branch's dist/, to compare).
        #[arg(long, value_name = "DIR")]
        dist: Option<PathBuf>,
    },
    /// Check every file in dist/ against its bootloader's boot contract and its flash
    /// budget, and the README's size tables against dist/ (fails when stale).
    Verify,
    /// Rewrite the README's size tables (sizes, text by crate) from the ELFs in dist/.
    Readme,
    /// Build the m4-bench programs, count their instructions under QEMU (m4count) and print
    /// the named figures; with --check fail when a figure marked `<!-- m4:NAME -->` in a
    /// Markdown file differs, with --write rewrite them.
    Figures {
        /// Fail (exit 1) when a marked figure in the docs is stale.
        #[arg(long, conflicts_with = "write")]
        check: bool,
        /// Rewrite every marked figure in the docs.
        #[arg(long)]
        write: bool,
    },
    /// Build the web ground station from a clone: the wasm target if missing, the decoder
    /// and its bindings (`wasm`), the app's npm packages (no browser download) and the app
    /// into telemetry/ground-station/dist.
    Web {
        /// Then run its unit tests and its browser tests (Debian's Chromium, against
        /// `taulink-sim --serve`).
        #[arg(long)]
        test: bool,
    },
    /// Build the ground station's decoder for the browser and write its JavaScript
    /// bindings into telemetry/ground-station/src/wasm (what `npm run wasm` runs).
    Wasm,
}

#[derive(Subcommand, Debug)]
enum Image {
    /// The flight controller (STM32F405; BrushedSparky unless told otherwise).
    Flight {
        /// Build for the Sparky2 board instead of the BrushedSparky.
        #[arg(long)]
        sparky2: bool,
        /// Link at 0x08020000 behind the Tau Labs bootloader instead of at 0x08000000.
        #[arg(long)]
        bootloader: bool,
    },
    /// The TauLink module (nRF52840).
    Module {
        /// Link at 0x26000 behind a UF2 bootloader (nice!nano and friends) and write a .uf2.
        #[arg(long)]
        uf2: bool,
    },
}

/// `--image`'s check: the name of a variant.
fn image_name(name: &str) -> Result<String, String> {
    match VARIANTS.iter().find(|v| v.name == name) {
        Some(v) => Ok(v.name.to_string()),
        None => {
            let names: Vec<&str> = VARIANTS.iter().map(|v| v.name).collect();
            Err(format!("the images are {}", names.join(", ")))
        }
    }
}

const TARGET: &str = "thumbv7em-none-eabihf";

/// One firmware variant: which package, which features, what to call the files.
struct Variant {
    package: &'static str,
    features: &'static [&'static str],
    name: &'static str,
    /// Write a UF2 file (nRF52840 behind a UF2 bootloader).
    uf2: bool,
    /// Write a Tau Labs `.tlfw` for this board type and revision.
    tlfw: Option<(u8, u8)>,
    /// The boot contract the files must keep.
    layout: &'static Layout,
    /// Shown in the per-crate breakdown: one variant of each build (the others are the
    /// same code linked for another starter).
    in_breakdown: bool,
}

const VARIANTS: &[Variant] = &[
    Variant {
        package: "flight-fw",
        features: &[],
        name: "flight-brushedsparky",
        uf2: false,
        tlfw: None,
        layout: &layout::F405_DIRECT,
        in_breakdown: true,
    },
    Variant {
        package: "flight-fw",
        features: &["sparky2"],
        name: "flight-sparky2",
        uf2: false,
        tlfw: None,
        layout: &layout::F405_DIRECT,
        in_breakdown: true,
    },
    Variant {
        package: "flight-fw",
        features: &["taulabs-bootloader"],
        name: "flight-brushedsparky-taulabs-bl",
        uf2: false,
        tlfw: Some((tlfw::BOARD_TYPE_SPARKY2, tlfw::REVISION_BRUSHEDSPARKY)),
        layout: &layout::F405_TAULABS,
        in_breakdown: false,
    },
    Variant {
        package: "flight-fw",
        features: &["sparky2", "taulabs-bootloader"],
        name: "flight-sparky2-taulabs-bl",
        uf2: false,
        tlfw: Some((tlfw::BOARD_TYPE_SPARKY2, tlfw::REVISION_SPARKY2)),
        layout: &layout::F405_TAULABS,
        in_breakdown: false,
    },
    Variant {
        package: "module-fw",
        features: &[],
        name: "module-nrf52840",
        uf2: false,
        tlfw: None,
        layout: &layout::NRF_PROBE,
        in_breakdown: true,
    },
    Variant {
        package: "module-fw",
        features: &["uf2"],
        name: "module-nrf52840-uf2",
        uf2: true,
        tlfw: None,
        layout: &layout::NRF_UF2,
        in_breakdown: false,
    },
];

/// Version tag written into `.tlfw` descriptors.
const TLFW_TAG: &str = concat!("taulink-", env!("CARGO_PKG_VERSION"));

fn workspace_root() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    root.canonicalize().unwrap_or(root)
}

fn target_dir() -> PathBuf {
    env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("target"))
}

fn build(package: &str, features: &[&str]) -> Result<PathBuf, String> {
    let cargo = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(workspace_root()).args([
        "build",
        "--release",
        "--target",
        TARGET,
        "-p",
        package,
    ]);
    if !features.is_empty() {
        cmd.args(["--features", &features.join(",")]);
    }
    let status = cmd.status().map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err(format!("building {package} failed"));
    }
    Ok(target_dir().join(TARGET).join("release").join(package))
}

/// Builds every m4-bench program (release, for the M4).
fn build_benches() -> Result<(), String> {
    let cargo = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .current_dir(workspace_root())
        .args(["build", "--release", "--target", TARGET, "-p", "m4-bench"])
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err("building m4-bench failed".into());
    }
    Ok(())
}

fn write_outputs(variant: &Variant, elf_path: &Path, dist: &Path) -> Result<(), String> {
    let elf = fs::read(elf_path).map_err(|e| format!("{}: {e}", elf_path.display()))?;
    let segments = elf::load_segments(&elf).map_err(|e| format!("{}: {e}", elf_path.display()))?;
    let sizes = elf::sizes(&elf).map_err(|e| e.to_string())?;
    let (start, bin) = formats::to_bin(&segments);
    let write = |ext: &str, bytes: &[u8]| {
        let path = dist.join(format!("{}.{ext}", variant.name));
        fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))
    };
    write("elf", &elf)?;
    write("bin", &bin)?;
    write("hex", formats::to_ihex(&segments).as_bytes())?;
    if variant.uf2 {
        write(
            "uf2",
            &formats::to_uf2(&segments, formats::UF2_FAMILY_NRF52840),
        )?;
    }
    if let Some((board_type, revision)) = variant.tlfw {
        write("tlfw", &tlfw::package(&bin, board_type, revision, TLFW_TAG))?;
    }
    println!(
        "{:<34} text {:>7}  data {:>5}  bss {:>6}  flash from 0x{start:08X}, .bin {} bytes",
        variant.name,
        sizes.text,
        sizes.data,
        sizes.bss,
        bin.len()
    );
    Ok(())
}

fn dist() -> Result<(), String> {
    let dist = workspace_root().join("dist");
    fs::create_dir_all(&dist).map_err(|e| format!("{}: {e}", dist.display()))?;
    let mut built = Vec::new();
    for v in VARIANTS {
        let elf = build(v.package, v.features)?;
        // The next variant of the same package overwrites the ELF: keep a copy first.
        let keep = dist.join(format!("{}.elf", v.name));
        fs::copy(&elf, &keep).map_err(|e| format!("{}: {e}", keep.display()))?;
        built.push((v, keep));
    }
    println!("\nflashable files in {}:", dist.display());
    for (v, elf) in built {
        write_outputs(v, &elf, &dist)?;
    }
    Ok(())
}

fn size() -> Result<(), String> {
    let dist = workspace_root().join("dist");
    for v in VARIANTS {
        let path = dist.join(format!("{}.elf", v.name));
        let Ok(elf) = fs::read(&path) else {
            println!("{:<34} (not built: run `cargo xtask dist`)", v.name);
            continue;
        };
        let s = elf::sizes(&elf).map_err(|e| format!("{}: {e}", path.display()))?;
        println!(
            "{:<34} text {:>7}  data {:>5}  bss {:>6}",
            v.name, s.text, s.data, s.bss
        );
    }
    Ok(())
}

/// A README block `cargo xtask readme` writes and `verify` checks: between two markers.
struct Block {
    begin: &'static str,
    end: &'static str,
}

/// The sizes table: every variant's flash, text against its budget, and static RAM.
const SIZES: Block = Block {
    begin: "<!-- xtask sizes: begin (cargo xtask readme writes this table) -->",
    end: "<!-- xtask sizes: end -->",
};

/// The text by crate of one variant of each build (`cargo xtask size-report`).
const BY_CRATE: Block = Block {
    begin: "<!-- xtask text-by-crate: begin (cargo xtask readme writes this table) -->",
    end: "<!-- xtask text-by-crate: end -->",
};

/// One variant's ELF from dist/.
fn dist_elf(v: &Variant) -> Result<Vec<u8>, String> {
    elf_in(&workspace_root().join("dist"), v)
}

/// One variant's ELF from the folder `dir`.
fn elf_in(dir: &Path, v: &Variant) -> Result<Vec<u8>, String> {
    let path = dir.join(format!("{}.elf", v.name));
    fs::read(&path).map_err(|e| format!("{}: {e} (run `cargo xtask dist`)", path.display()))
}

/// What the sizes table and the budget checks read from one image.
struct Usage {
    sizes: elf::Sizes,
    /// Bytes loaded into flash (text and the initial values of data).
    flash: u32,
}

fn usage(v: &Variant, image: &[u8]) -> Result<Usage, String> {
    let shown = |e: elf::ElfError| format!("{}.elf: {e}", v.name);
    let segments = elf::load_segments(image).map_err(shown)?;
    Ok(Usage {
        sizes: elf::sizes(image).map_err(shown)?,
        flash: segments.iter().map(|s| s.data.len() as u32).sum(),
    })
}

/// The sizes table for the README, from the ELFs in dist/.
fn sizes_table() -> Result<String, String> {
    let mut t = String::from(
        "| image | flash from | flash used | of the bootloader's partition | text | of the \
         text budget | data | bss | SRAM left to the stack |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for v in VARIANTS {
        let u = usage(v, &dist_elf(v)?)?;
        let s = u.sizes;
        let partition = budget::partition(v.layout).map_or("—".to_string(), |p| {
            format!("{} of {p} B", budget::percent(u.flash, p))
        });
        let text_budget = budget::text_budget(v.package).map_or("—".to_string(), |b| {
            format!("{} of {b} B", budget::percent(s.text, b))
        });
        let ram = v.layout.ram.end - v.layout.ram.start;
        let left = ram.saturating_sub(s.data + s.bss);
        t.push_str(&format!(
            "| `{}` | 0x{:08X} | {} B | {partition} | {} B | {text_budget} | {} B | {} B | {left} B of {ram} B |\n",
            v.name, v.layout.origin, u.flash, s.text, s.data, s.bss
        ));
    }
    Ok(t)
}

/// Crates under this many bytes in every image are one row of the breakdown.
const CRATE_ROW_MIN: u32 = 1024;
/// Generic code instantiated for another crate gets its own row from this many bytes.
const INSTANCE_ROW_MIN: u32 = 2048;

/// The text-by-crate table for the README: crates by their largest share, generic code
/// made for another crate below its crate.
fn crate_table() -> Result<String, String> {
    let shown: Vec<&Variant> = VARIANTS.iter().filter(|v| v.in_breakdown).collect();
    let mut reports = Vec::new();
    for v in &shown {
        let report =
            size_report::breakdown(&dist_elf(v)?).map_err(|e| format!("{}.elf: {e}", v.name))?;
        reports.push(report);
    }
    let largest =
        |get: &dyn Fn(&size_report::Breakdown) -> u32| reports.iter().map(get).max().unwrap_or(0);
    let mut crates: Vec<&String> = reports.iter().flat_map(|r| r.by_crate.keys()).collect();
    crates.sort();
    crates.dedup();
    crates
        .sort_by_key(|c| std::cmp::Reverse(largest(&|r| r.by_crate.get(*c).copied().unwrap_or(0))));
    let mut t = format!(
        "| crate (generic code: ↳ instantiated for) | {} |\n|---|{}\n",
        shown
            .iter()
            .map(|v| format!("`{}`", v.name))
            .collect::<Vec<_>>()
            .join(" | "),
        "---:|".repeat(shown.len())
    );
    let row = |t: &mut String, label: &str, cells: &[u32]| {
        let cells: Vec<String> = cells.iter().map(u32::to_string).collect();
        t.push_str(&format!("| {label} | {} |\n", cells.join(" | ")));
    };
    let each = |get: &dyn Fn(&size_report::Breakdown) -> u32| -> Vec<u32> {
        reports.iter().map(get).collect()
    };
    let (mut small, mut small_count) = (vec![0u32; reports.len()], 0);
    for c in crates {
        let bytes = each(&|r| r.by_crate.get(c).copied().unwrap_or(0));
        if bytes.iter().all(|&b| b < CRATE_ROW_MIN) {
            for (sum, b) in small.iter_mut().zip(&bytes) {
                *sum += b;
            }
            small_count += 1;
            continue;
        }
        row(&mut t, c, &bytes);
        let mut users: Vec<&String> = reports
            .iter()
            .flat_map(|r| r.by_instance.keys())
            .filter(|(k, _)| k == c)
            .map(|(_, u)| u)
            .collect();
        users.sort();
        users.dedup();
        for u in users {
            let key = (c.clone(), u.clone());
            let bytes = each(&|r| r.by_instance.get(&key).copied().unwrap_or(0));
            if bytes.iter().any(|&b| b >= INSTANCE_ROW_MIN) {
                row(&mut t, &format!("↳ {u}"), &bytes);
            }
        }
    }
    let small_label = format!("{small_count} crates under {CRATE_ROW_MIN} B each");
    row(&mut t, &small_label, &small);
    row(
        &mut t,
        "no symbol (merged strings, padding)",
        &each(&|r| r.between_symbols()),
    );
    row(&mut t, "**text**", &each(&|r| r.text));
    Ok(t)
}

/// `readme` with `block`'s content replaced, or an error if its markers are missing.
fn readme_with(readme: &str, block: &Block, content: &str) -> Result<String, String> {
    let start = readme
        .find(block.begin)
        .ok_or_else(|| format!("README.md has no `{}` marker", block.begin))?
        + block.begin.len();
    let end = readme
        .get(start..)
        .and_then(|rest| rest.find(block.end))
        .ok_or_else(|| format!("README.md has no `{}` marker", block.end))?
        + start;
    Ok(format!(
        "{}\n{content}{}",
        readme.get(..start).unwrap_or_default(),
        readme.get(end..).unwrap_or_default()
    ))
}

/// The README with both generated blocks from dist/.
fn readme_generated(text: &str) -> Result<String, String> {
    let text = readme_with(text, &SIZES, &sizes_table()?)?;
    readme_with(&text, &BY_CRATE, &crate_table()?)
}

fn readme() -> Result<(), String> {
    let path = workspace_root().join("README.md");
    let text = fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    fs::write(&path, readme_generated(&text)?).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("size tables in {} updated", path.display());
    Ok(())
}

fn size_report(image: Option<&str>, top: usize, dir: &Path) -> Result<(), String> {
    let chosen: Vec<&Variant> = VARIANTS
        .iter()
        .filter(|v| image.map_or(v.in_breakdown, |name| v.name == name))
        .collect();
    for v in chosen {
        let r =
            size_report::breakdown(&elf_in(dir, v)?).map_err(|e| format!("{}.elf: {e}", v.name))?;
        println!(
            "{}: text {} B ({} B under no symbol: merged strings, padding)",
            v.name,
            r.text,
            r.between_symbols()
        );
        let mut crates: Vec<(&String, &u32)> = r.by_crate.iter().collect();
        crates.sort_by_key(|&(c, b)| (std::cmp::Reverse(*b), c.clone()));
        for (c, b) in crates {
            println!("  {b:>8} B {:>8}  {c}", budget::percent(*b, r.text));
            let mut users: Vec<(&String, &u32)> = r
                .by_instance
                .iter()
                .filter(|((k, _), _)| k == c)
                .map(|((_, u), b)| (u, b))
                .collect();
            users.sort_by_key(|&(u, b)| (std::cmp::Reverse(*b), u.clone()));
            for (u, b) in users {
                println!("  {b:>8} B {:>8}    ↳ instantiated for {u}", "");
            }
        }
        println!("  largest symbols:");
        for item in r.items.iter().take(top) {
            println!(
                "  {:>8} B  {:<18} {}",
                item.size,
                item.owner.krate,
                size_report::short_name(&item.name, 160)
            );
        }
        println!();
    }
    Ok(())
}

fn verify() -> Result<(), String> {
    let dist = workspace_root().join("dist");
    let read = |v: &Variant, ext: &str| fs::read(dist.join(format!("{}.{ext}", v.name))).ok();
    let mut failed = 0;
    for v in VARIANTS {
        let Some(elf) = read(v, "elf") else {
            println!(
                "FAIL {:<34} dist/{0}.elf missing: run `cargo xtask dist`",
                v.name
            );
            failed += 1;
            continue;
        };
        let (bin, uf2, tl) = (read(v, "bin"), read(v, "uf2"), read(v, "tlfw"));
        let mut problems = Vec::new();
        if v.tlfw.is_some() && tl.is_none() {
            problems.push("no .tlfw written".to_string());
        }
        let files = verify::Files {
            elf: &elf,
            bin: bin.as_deref(),
            uf2: uf2.as_deref(),
            tlfw: tl.as_deref().zip(v.tlfw).map(|(f, (t, r))| (f, t, r)),
        };
        problems.extend(verify::check(v.layout, &files));
        match usage(v, &elf) {
            Ok(u) => problems.extend(budget::problems(v.package, v.layout, u.sizes.text, u.flash)),
            Err(e) => problems.push(e),
        }
        println!(
            "{} {:<34} behind {}{}",
            if problems.is_empty() { "ok  " } else { "FAIL" },
            v.name,
            v.layout.starter,
            if problems.is_empty() {
                ", within its flash budget"
            } else {
                ""
            }
        );
        for p in &problems {
            println!("       {p}");
        }
        failed += usize::from(!problems.is_empty());
    }
    // The README's sizes are generated; a stale table is a failure, not a footnote.
    let path = workspace_root().join("README.md");
    let text = fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    if readme_generated(&text)? != text {
        println!("FAIL README.md size tables are stale: run `cargo xtask readme`");
        failed += 1;
    } else {
        println!("ok   README.md size tables match dist/");
    }
    if failed > 0 {
        return Err(format!("{failed} check(s) failed"));
    }
    Ok(())
}

fn run(task: &Task) -> Result<(), String> {
    match task {
        Task::Build(image) => {
            let (package, wanted) = match *image {
                Image::Flight {
                    sparky2,
                    bootloader,
                } => (
                    "flight-fw",
                    vec![(sparky2, "sparky2"), (bootloader, "taulabs-bootloader")],
                ),
                Image::Module { uf2 } => ("module-fw", vec![(uf2, "uf2")]),
            };
            let features: Vec<&str> = wanted
                .into_iter()
                .filter_map(|(on, f)| on.then_some(f))
                .collect();
            let elf = build(package, &features)?;
            println!("{}", elf.display());
            Ok(())
        }
        Task::Dist => dist(),
        Task::Size => size(),
        Task::SizeReport { image, top, dist } => {
            let dir = dist
                .clone()
                .unwrap_or_else(|| workspace_root().join("dist"));
            size_report(image.as_deref(), *top, &dir)
        }
        Task::Verify => verify(),
        Task::Readme => readme(),
        Task::Figures { check, write } => {
            let mode = match (check, write) {
                (true, _) => figures::Mode::Check,
                (_, true) => figures::Mode::Write,
                _ => figures::Mode::Print,
            };
            build_benches()?;
            let elf_dir = target_dir().join(TARGET).join("release");
            figures::run(&workspace_root(), &elf_dir, mode)
        }
        Task::Web { test } => web::web(&workspace_root(), &target_dir(), web::Web { test: *test }),
        Task::Wasm => web::wasm(&workspace_root(), &target_dir()),
    }
}

fn main() -> ExitCode {
    // clap prints --help/--version (exit 0) and usage errors with a suggestion (exit 2).
    let cli = Cli::parse();
    match run(&cli.task) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn readme_blocks_are_replaced_between_their_markers() {
        let text = format!(
            "intro\n{}\nold table\n{}\nmid\n{}\nold\n{}\noutro\n",
            SIZES.begin, SIZES.end, BY_CRATE.begin, BY_CRATE.end
        );
        let new = readme_with(&text, &SIZES, "| new |\n").unwrap();
        assert_eq!(
            new,
            format!(
                "intro\n{}\n| new |\n{}\nmid\n{}\nold\n{}\noutro\n",
                SIZES.begin, SIZES.end, BY_CRATE.begin, BY_CRATE.end
            )
        );
        assert_eq!(readme_with(&new, &SIZES, "| new |\n").unwrap(), new);
        let both = readme_with(&new, &BY_CRATE, "| c |\n").unwrap();
        assert!(both.contains(&format!("{}\n| c |\n{}", BY_CRATE.begin, BY_CRATE.end)));
        assert!(readme_with("no markers", &SIZES, "x").is_err());
    }

    #[test]
    fn every_package_has_a_budget_and_one_variant_of_each_build_is_broken_down() {
        for v in VARIANTS {
            assert!(budget::text_budget(v.package).is_some(), "{}", v.name);
        }
        let shown: Vec<_> = VARIANTS
            .iter()
            .filter(|v| v.in_breakdown)
            .map(|v| v.name)
            .collect();
        assert_eq!(
            shown,
            ["flight-brushedsparky", "flight-sparky2", "module-nrf52840"]
        );
    }

    #[test]
    fn every_layout_has_a_sparky2_build() {
        let flight: Vec<_> = VARIANTS
            .iter()
            .filter(|v| v.package == "flight-fw")
            .collect();
        for layout in [&layout::F405_DIRECT, &layout::F405_TAULABS] {
            assert!(
                flight
                    .iter()
                    .any(|v| std::ptr::eq(v.layout, layout) && v.features.contains(&"sparky2")),
                "no Sparky2 build behind {}",
                layout.starter
            );
        }
    }
}
